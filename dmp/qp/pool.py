"""Candidate constraint rows on the dense grid, addressed by integer ids (for the cutting-plane solver).

Every inequality row of every constraint at every dense sample has a flat id: constraint ``c``
owns ids ``offset[c] .. offset[c] + m_c * K_c``, row ``j`` of its sample position ``p`` (in the
constraint's samples ``k``) is ``offset[c] + j * K_c + p``, so each row's time series is
contiguous. Rows are only materialised for the ids asked for; residuals come from a rollout of a
subset of samples (a :class:`Level`): the constraint grid, the samples it points at, or all.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from dmp.affine import AffineRollout
from dmp.qp.constraints.base import Coefficients, Constraint

Ids = NDArray[np.intp]


@dataclass(frozen=True)
class Level:
    """Rollout data on the dense samples ``s`` (S,), and where each constraint's samples fall in ``s``.

    ``pos[c]`` are positions in the constraint's samples ``k`` that lie in ``s``, ``loc[c]`` their
    index in ``s`` (a slice where contiguous, so gathers become views).
    """

    s: NDArray[np.intp]
    x_free: NDArray[np.float64]
    v_free: NDArray[np.float64]
    gx: NDArray[np.float64]
    gv: NDArray[np.float64]
    pos: list[NDArray[np.intp]]
    loc: list[NDArray[np.intp] | slice]

    @classmethod
    def of(cls, aff: AffineRollout, ks: Sequence[NDArray[np.intp]], s: NDArray[np.intp] | None) -> Level:
        """Level on samples ``s`` (sorted; None for every sample) for constraints sampled at ``ks``."""
        if s is None:
            s = np.arange(aff.t.size)
            return cls(s, aff.x_free, aff.v_free, aff.Gx, aff.Gv, [np.arange(k.size) for k in ks],
                       [_as_slice(k) for k in ks])
        mask = np.zeros(aff.t.size, dtype=bool)
        mask[s] = True
        where = np.cumsum(mask) - 1
        pos = [np.flatnonzero(mask[k]) for k in ks]
        loc = [_as_slice(where[k[p]]) for k, p in zip(ks, pos, strict=True)]
        return cls(s, aff.x_free[s], aff.v_free[s], np.ascontiguousarray(aff.Gx[s]),
                   np.ascontiguousarray(aff.Gv[s]), pos, loc)


def _as_slice(idx: NDArray[np.intp]) -> NDArray[np.intp] | slice:
    """``idx`` (increasing) as a slice when it is a contiguous run."""
    if idx.size and int(idx[-1]) - int(idx[0]) == idx.size - 1:
        return slice(int(idx[0]), int(idx[-1]) + 1)
    return idx


@dataclass(frozen=True)
class _Terms:
    """One constraint's coefficients on a level, laid out for residuals without gathers:
    ``neg_bound`` (m, P) or (m, 1) and, per dimension d, ``pos[d]`` / ``vel[d]`` (m, P) or (m, 1)."""

    neg_bound: NDArray[np.float64]
    pos: list[NDArray[np.float64]] | None
    vel: list[NDArray[np.float64]] | None

    @classmethod
    def of(cls, co: Coefficients, pos: NDArray[np.intp]) -> _Terms:
        def per_dim(a: NDArray[np.float64] | None) -> list[NDArray[np.float64]] | None:
            if a is None:
                return None
            if _const(a):
                return [np.ascontiguousarray(a[0, :, d, None]) for d in range(a.shape[2])]
            return [np.ascontiguousarray(a[pos, :, d].T) for d in range(a.shape[2])]

        nb = -(co.bound[:1].T if _const(co.bound) else co.bound[pos].T)
        return cls(np.ascontiguousarray(nb), per_dim(co.a_pos), per_dim(co.a_vel))


def _const(a: NDArray[np.float64]) -> bool:
    """Whether ``a`` (K, ...) repeats one value along its first axis without copies (a broadcast)."""
    return a.shape[0] > 0 and a.strides[0] == 0


@dataclass
class RowPool:
    """Every inequality row of every constraint at every dense sample, for one linearisation path."""

    constraints: Sequence[Constraint]
    coeffs: list[Coefficients]
    aff: AffineRollout
    offset: NDArray[np.intp]
    """(C + 1,) first id of each constraint; equality constraints own no ids."""
    _prep: dict[int, tuple[Level, list[tuple[int, _Terms]]]] = field(default_factory=dict, repr=False)

    @classmethod
    def build(cls, constraints: Sequence[Constraint], aff: AffineRollout, x_lin: NDArray[np.float64]) -> RowPool:
        coeffs = [c.coefficients(aff.t, x_lin) for c in constraints]
        sizes = [0 if c.equality else co.bound.size for c, co in zip(constraints, coeffs, strict=True)]
        return cls(constraints, coeffs, aff, np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp))

    @property
    def size(self) -> int:
        return int(self.offset[-1])

    @property
    def ks(self) -> list[NDArray[np.intp]]:
        return [co.k for co in self.coeffs]

    def _inequalities(self) -> list[int]:
        return [i for i, (c, co) in enumerate(zip(self.constraints, self.coeffs, strict=True))
                if not c.equality and co.k.size]

    def _terms(self, level: Level, cache: bool) -> list[tuple[int, _Terms]]:
        key = id(level)
        if key in self._prep and self._prep[key][0] is level:
            return self._prep[key][1]
        terms = [(ci, _Terms.of(self.coeffs[ci], level.pos[ci])) for ci in self._inequalities()
                 if level.pos[ci].size]
        if cache:
            self._prep[key] = (level, terms)
        return terms

    def residuals(
        self, w: NDArray[np.float64], level: Level, cache: bool = True
    ) -> list[tuple[int, NDArray[np.float64]]]:
        """Residuals ``(c, R)`` of every inequality constraint ``c`` on the level's samples, ``R`` of
        shape (m_c, len(level.pos[c])) (<= 0 is satisfied), for flat weights ``w``. The level's
        coefficient layout is kept for the next call when ``cache``."""
        wm = np.asarray(w).reshape(-1, self.aff.n_dims) @ self.aff.M.T
        x = level.x_free + level.gx @ wm
        v = level.v_free + level.gv @ wm
        out = []
        for ci, t in self._terms(level, cache):
            loc = level.loc[ci]
            r = t.neg_bound
            for coef, xv in ((t.pos, x), (t.vel, v)):
                if coef is not None:
                    for d, c in enumerate(coef):
                        r = r + c * xv[loc, d]
            out.append((ci, np.broadcast_to(r, (r.shape[0], level.pos[ci].size))))
        return out

    def ids(self, ci: int, j: NDArray[np.intp], p: NDArray[np.intp]) -> Ids:
        """Ids of rows ``j`` at sample positions ``p`` of constraint ``ci``."""
        return self.offset[ci] + j * self.coeffs[ci].k.size + p

    def peaks(
        self, res: list[tuple[int, NDArray[np.float64]]], level: Level, threshold: float, neighbours: int = 0
    ) -> Ids:
        """Ids of the local maxima in time (over the level's samples) of rows violated by more than
        ``threshold``; with ``neighbours`` > 0 also the rows that many dense samples either side."""
        out = []
        for ci, r in res:
            peak = r > threshold
            if not peak.any():
                continue
            peak[:, 1:] &= r[:, 1:] >= r[:, :-1]
            peak[:, :-1] &= r[:, :-1] >= r[:, 1:]
            j, p = np.nonzero(peak)
            p = level.pos[ci][p]
            if neighbours:
                kk = self.coeffs[ci].k.size
                p = (p[:, None] + np.arange(-neighbours, neighbours + 1)).ravel()
                j = np.repeat(j, 2 * neighbours + 1)
                ok = (p >= 0) & (p < kk)
                j, p = j[ok], p[ok]
            out.append(self.ids(ci, j, p))
        return np.concatenate(out) if out else np.zeros(0, dtype=np.intp)

    def suspects(self, res: list[tuple[int, NDArray[np.float64]]], grid: Level, tol: float) -> NDArray[np.intp]:
        """Dense samples that may violate a row, judged from the residuals ``res`` on the ``grid``
        level (every ``factor``-th dense sample).

        A stretch between two grid samples is suspect when its larger end residual plus half the
        second differences there (four times the interpolation-error estimate of a smooth residual)
        exceeds ``tol``; dense samples of a constraint outside its grid samples are always suspects.
        Only a filter: the caller confirms with a full pass.
        """
        mask = np.zeros(self.aff.t.size, dtype=bool)
        cover = np.zeros(mask.size + 1, dtype=np.int64)
        seen = set()
        for ci, r in res:
            seen.add(ci)
            k = self.coeffs[ci].k
            kg = k[grid.pos[ci]]
            if kg.size < 2:
                mask[k] = True
                continue
            d2 = np.zeros_like(r)
            d2[:, 1:-1] = np.abs(r[:, :-2] - 2.0 * r[:, 1:-1] + r[:, 2:])
            top = (r + 0.5 * d2).max(axis=0)
            bad = np.flatnonzero(np.maximum(top[:-1], top[1:]) > tol)
            np.add.at(cover, kg[bad], 1)
            np.add.at(cover, kg[bad + 1] + 1, -1)
            mask[k[(k < kg[0]) | (k > kg[-1])]] = True
        for ci in self._inequalities():
            if ci not in seen:  # no sample on the grid at all
                mask[self.coeffs[ci].k] = True
        mask |= np.cumsum(cover[:-1]) > 0
        return np.flatnonzero(mask)

    def decode(self, ids: Ids) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
        """Constraint, row and sample position of each id."""
        ci = np.searchsorted(self.offset, ids, side="right") - 1
        kk = np.array([co.k.size for co in self.coeffs], dtype=np.intp)[ci]
        local = ids - self.offset[ci]
        return ci, local // kk, local % kk

    def rows(self, ids: Ids) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``G`` (len(ids), N*n) and ``h`` for the given ids, in order."""
        nw = self.aff.n_weights
        g, h = np.zeros((ids.size, nw)), np.zeros(ids.size)
        if ids.size == 0:
            return g, h
        ci, j, p = self.decode(ids)
        for c in np.unique(ci).tolist():
            sel = np.flatnonzero(ci == c)
            rows = self.coeffs[c].rows(self.aff, p[sel], j[sel])
            g[sel], h[sel] = rows.G, rows.h
        return g, h

    def equality_rows(self) -> tuple[NDArray[np.float64], NDArray[np.float64], list[str]]:
        """Every equality row ``A w = b`` and its family."""
        gs, hs, fams = [np.zeros((0, self.aff.n_weights))], [np.zeros(0)], []
        for c, co in zip(self.constraints, self.coeffs, strict=True):
            if c.equality and co.k.size:
                rows = co.all_rows(self.aff)
                gs.append(rows.G)
                hs.append(rows.h)
                fams += [c.family] * rows.h.size
        return np.vstack(gs), np.concatenate(hs), fams

    def families(self, ids: Ids) -> set[str]:
        if ids.size == 0:
            return set()
        return {self.constraints[c].family for c in np.unique(self.decode(ids)[0]).tolist()}

    def coarse_ids(self, stride: int) -> Ids:
        """Every inequality row at every ``stride``-th dense sample of each constraint (and its last)."""
        out = []
        for ci in self._inequalities():
            kk, m = self.coeffs[ci].k.size, self.coeffs[ci].bound.shape[1]
            p = np.unique(np.append(np.arange(0, kk, stride), kk - 1))
            out.append(self.ids(ci, np.repeat(np.arange(m), p.size), np.tile(p, m)))
        return np.concatenate(out) if out else np.zeros(0, dtype=np.intp)
