"""Candidate constraint rows on the dense grid, addressed by integer ids (for the cutting-plane solver).

Every inequality row of every constraint at every dense sample has a flat id: constraint ``c``
owns ids ``offset[c] .. offset[c] + m_c * K_c``, row ``j`` of its sample position ``p`` (in the
constraint's samples ``k``) is ``offset[c] + j * K_c + p``. Rows are only materialised for the ids
asked for. For residuals, the rows of all constraints are stacked as *series* (one per constraint
row ``j``) over all dense samples, with neutral entries where a constraint does not apply, so that
the residuals of every row on any subset of samples (a :class:`Samples`) and their violated local
maxima take one pass of the dual active-set core (:meth:`RowPool.scan`, compiled or its NumPy
fallback, :mod:`tooltransfer.dmp.qp.native`; :meth:`RowPool.residuals` and :meth:`RowPool.peaks` are the same
in plain NumPy), whatever the number of constraints; the rows of new ids are built there too
(:meth:`RowPool.rows`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.affine import AffineRollout
from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint
from tooltransfer.dmp.qp.gi_state import PoolArrays
from tooltransfer.dmp.qp.native import core

Ids = NDArray[np.intp]
Cols = NDArray[np.intp] | slice

OFF = -1e30
"""Residual of a series at a sample where its constraint does not apply (finite, so differences stay finite)."""


@dataclass(frozen=True)
class Samples:
    """The affine rollout restricted to the dense samples ``cols`` (a slice or sorted indices)."""

    cols: Cols
    idx: NDArray[np.intp]
    """the dense sample indices."""
    x_free: NDArray[np.float64]
    v_free: NDArray[np.float64]
    gx: NDArray[np.float64]
    gv: NDArray[np.float64]

    @classmethod
    def of(cls, aff: AffineRollout, cols: Cols) -> Samples:
        idx = np.arange(aff.t.size)[cols] if isinstance(cols, slice) else cols
        if isinstance(cols, slice) and cols == slice(None):
            return cls(cols, idx, aff.x_free, aff.v_free, aff.Gx, aff.Gv)
        return cls(cols, idx, aff.x_free[cols], aff.v_free[cols], np.ascontiguousarray(aff.Gx[cols]),
                   np.ascontiguousarray(aff.Gv[cols]))


@dataclass
class RowPool:
    """Every inequality row of every constraint at every dense sample, for one linearisation path.

    Attributes (series ``s`` = one row ``j`` of one inequality constraint, dense samples ``t``):
        neg_bound: (S, T) ``-bound`` (``OFF`` where the constraint does not apply).
        a_pos: (P, n, T) position coefficients of series [0, P) (zero where it does not apply).
        a_vel: (S - vel_from, n, T) velocity coefficients of series [vel_from, S).
        id_of: (S, T) row id (-1 where it does not apply).
    """

    constraints: Sequence[Constraint]
    coeffs: list[Coefficients]
    samples_of: list[NDArray[np.intp]]
    """each constraint's samples of the dense grid (:meth:`Constraint.samples`)."""
    aff: AffineRollout
    offset: NDArray[np.intp]
    first_series: NDArray[np.intp]
    k_start: NDArray[np.intp]
    neg_bound: NDArray[np.float64]
    a_pos: NDArray[np.float64]
    a_vel: NDArray[np.float64]
    id_of: NDArray[np.intp]
    vel_from: int
    series_of: NDArray[np.int64]
    """(ids,) series of each row id."""
    sample_of: NDArray[np.int64]
    """(ids,) dense sample of each row id."""
    _arrays: PoolArrays | None = None
    _eq: tuple[NDArray[np.float64], NDArray[np.float64], list[str]] | None = None
    _out: tuple[NDArray[np.int32], NDArray[np.int64]] | None = None

    @classmethod
    def build(
        cls, constraints: Sequence[Constraint], aff: AffineRollout, x_lin: NDArray[np.float64],
        previous: RowPool | None = None,
    ) -> RowPool:
        """Rows linearised along ``x_lin`` (T, n). With ``previous`` (a pool of the same constraints
        and grid, given up by the caller) its arrays are reused and only linearised constraints
        are refreshed."""
        before: list[Coefficients | None] = list(previous.coeffs) if previous else [None] * len(constraints)
        # each constraint's samples of the grid, found once per pool: ``c.coefficients`` is ``c._coefficients``
        # at ``c.samples(aff.t)``
        ks = previous.samples_of if previous else [c.samples(aff.t) for c in constraints]
        coeffs: list[Coefficients] = [c._coefficients(k, aff.t, x_lin) if (co is None or c.linearised) else co
                                      for c, k, co in zip(constraints, ks, before, strict=True)]
        if previous is not None:
            pool = previous
            pool.coeffs = coeffs
            moved = False  # whether a refilled constraint's samples or rows changed (its row tables are rewritten)
            for ci, c in enumerate(constraints):
                if c.linearised and not c.equality:
                    old = before[ci]
                    new = coeffs[ci]
                    same = old is not None and old.bound.shape == new.bound.shape and (
                        old.k is new.k or np.array_equal(old.k, new.k))
                    pool._fill(ci, tables=not same)
                    moved |= not same
            if moved and pool._arrays is not None:
                pool._arrays.check_tables()  # the refill rewrote the row tables the core reads
            return pool
        ineq = [not c.equality for c in constraints]
        sizes = [co.bound.size if q else 0 for co, q in zip(coeffs, ineq, strict=True)]
        t, n = aff.t.size, aff.n_dims
        # series ordered by kind: position-only, both, velocity-only, so that the rows with
        # position terms are series [0, n_pos) and those with velocity terms [n_pos_only, S)
        kind = [(co.a_vel is not None) - (co.a_pos is not None) + 1 if q else -1
                for co, q in zip(coeffs, ineq, strict=True)]
        first = np.zeros(len(constraints), dtype=np.intp)
        n_kind = [0, 0, 0]
        for want in range(3):
            for ci, kd in enumerate(kind):
                if kd == want:
                    first[ci] = sum(n_kind)
                    n_kind[want] += coeffs[ci].bound.shape[1]
        s = sum(n_kind)
        pool = cls(
            constraints, coeffs, ks, aff,
            offset=np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp),
            first_series=first,
            k_start=np.concatenate([[0], np.cumsum([co.k.size for co in coeffs])]).astype(np.intp),
            neg_bound=np.full((s, t), OFF),
            a_pos=np.zeros((n_kind[0] + n_kind[1], n, t)),
            a_vel=np.zeros((n_kind[1] + n_kind[2], n, t)),
            id_of=np.full((s, t), -1, dtype=np.intp),
            vel_from=n_kind[0],
            series_of=np.zeros(int(sum(sizes)), dtype=np.int64),
            sample_of=np.zeros(int(sum(sizes)), dtype=np.int64),
        )
        for ci, q in enumerate(ineq):
            if q:
                pool._fill(ci)
        return pool

    def _fill(self, ci: int, tables: bool = True) -> None:
        """Write constraint ``ci``'s coefficients into the series, and with ``tables`` its row ids'
        tables (``id_of``, ``series_of``, ``sample_of``: they depend on its samples and row count only)."""
        co, s0 = self.coeffs[ci], int(self.first_series[ci])
        m = co.bound.shape[1]
        kk = co.k.size
        k: NDArray[np.intp] | slice = co.k
        if kk and int(co.k[-1]) - int(co.k[0]) == kk - 1:  # a window: a slice writes much faster
            k = slice(int(co.k[0]), int(co.k[0]) + kk)
        self.neg_bound[s0:s0 + m, k] = -co.bound.T
        if co.a_pos is not None:
            self.a_pos[s0:s0 + m, :, k] = co.a_pos.transpose(1, 2, 0)
        if co.a_vel is not None:
            v0 = s0 - self.vel_from
            self.a_vel[v0:v0 + m, :, k] = co.a_vel.transpose(1, 2, 0)
        if not tables:
            return
        self.id_of[s0:s0 + m, k] = self.offset[ci] + np.arange(m)[:, None] * kk + np.arange(kk)
        ids = slice(int(self.offset[ci]), int(self.offset[ci + 1]))
        self.series_of[ids] = np.repeat(np.arange(s0, s0 + m), kk)
        self.sample_of[ids] = np.tile(co.k, m)

    @property
    def size(self) -> int:
        return int(self.offset[-1])

    def residuals(self, w: NDArray[np.float64], smp: Samples) -> NDArray[np.float64]:
        """Residuals (S, len(samples)) of every series at the samples (<= 0 is satisfied; about
        ``OFF`` where a constraint does not apply) for flat weights ``w``."""
        wm = np.asarray(w).reshape(-1, self.aff.n_dims) @ self.aff.M.T
        cols = smp.cols
        r = self.neg_bound[:, cols].copy()
        n_pos = self.a_pos.shape[0]
        for a, rows, base, g in ((self.a_pos, r[:n_pos], smp.x_free, smp.gx),
                                 (self.a_vel, r[self.vel_from:], smp.v_free, smp.gv)):
            if a.shape[0]:
                xv = base + g @ wm
                for d in range(xv.shape[1]):
                    rows += a[:, d, cols] * xv[:, d]
        return r

    def scan(
        self, w: NDArray[np.float64], smp: Samples, threshold: float, keep: bool = False
    ) -> tuple[Ids, NDArray[np.float64] | None]:
        """Ids of the local maxima in time (over the samples) of rows violated by more than
        ``threshold``, and with ``keep`` the residuals (as :meth:`residuals`): the same as
        :meth:`peaks` of :meth:`residuals`, in one pass of the core."""
        wm = np.asarray(w).reshape(-1, self.aff.n_dims) @ self.aff.M.T
        x = np.ascontiguousarray(smp.x_free + smp.gx @ wm)
        v = np.ascontiguousarray(smp.v_free + smp.gv @ wm)
        n_s, n_t = self.neg_bound.shape
        idx = np.ascontiguousarray(smp.idx, dtype=np.int64)
        res = np.empty((n_s, idx.size)) if keep else None
        buf = np.empty(max(1, idx.size))
        start, step = 0, 0
        if isinstance(smp.cols, slice):
            start, _, step = smp.cols.indices(n_t)
        if self._out is None:
            cap = max(256, 8 * n_s)
            self._out = (np.empty(cap, dtype=np.int32), np.empty(cap, dtype=np.int64))
        pa, gi = self._core_arrays(), core()
        while True:
            out_s, out_t = self._out
            count = gi.gi_scan(pa, x, v, threshold, res, out_s, out_t, idx, start, step, buf)
            if count <= out_s.size:
                return self.id_of[out_s[:count], out_t[:count]], res
            self._out = (np.empty(count, dtype=np.int32), np.empty(count, dtype=np.int64))

    def peak_cells(
        self, res: NDArray[np.float64], smp: Samples, threshold: float
    ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """Series and dense sample of the local maxima in time (over the samples) of rows violated
        by more than ``threshold``."""
        peak = res > threshold
        if not peak.any():
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        peak[:, 1:] &= res[:, 1:] >= res[:, :-1]
        peak[:, :-1] &= res[:, :-1] >= res[:, 1:]
        s, c = np.nonzero(peak)
        return s, smp.idx[c]

    def peaks(self, res: NDArray[np.float64], smp: Samples, threshold: float) -> Ids:
        """Ids of the local maxima in time (over the samples) of rows violated by more than ``threshold``."""
        s, t = self.peak_cells(res, smp, threshold)
        return self.id_of[s, t]

    def suspects(
        self, res: NDArray[np.float64], grid: Samples, tol: float, outside: NDArray[np.bool_]
    ) -> NDArray[np.intp]:
        """Dense samples that may violate a row, judged from the residuals ``res`` on the ``grid``
        samples (sorted); ``outside`` is :meth:`outside_grid` of the grid.

        A stretch between two grid samples is suspect when its larger end residual plus half the
        second differences there (four times the interpolation-error estimate of a smooth residual)
        exceeds ``tol``; dense samples of a constraint outside the span of its grid samples are
        always suspects. Only a filter: the caller confirms with a full pass.
        """
        if res.shape[0] == 0:
            return np.flatnonzero(outside)
        kg = grid.idx
        on = res > 0.5 * OFF
        d2 = np.zeros_like(res)
        inner = on[:, :-2] & on[:, 1:-1] & on[:, 2:]
        d2[:, 1:-1] = np.where(inner, np.abs(res[:, :-2] - 2.0 * res[:, 1:-1] + res[:, 2:]), 0.0)
        top = (res + 0.5 * d2).max(axis=0)
        bad = np.flatnonzero(np.maximum(top[:-1], top[1:]) > tol)
        cover = np.zeros(self.aff.t.size + 1, dtype=np.int64)
        np.add.at(cover, kg[bad], 1)
        np.add.at(cover, kg[bad + 1] + 1, -1)
        mask = np.cumsum(cover[:-1]) > 0
        return np.flatnonzero(mask | outside)

    def outside_grid(self, grid: Samples) -> NDArray[np.bool_]:
        """(T,) dense samples of a constraint outside the span of its samples on ``grid`` (all of
        them when fewer than two are on it)."""
        mask = np.zeros(self.aff.t.size, dtype=bool)
        on_grid = np.zeros(self.aff.t.size, dtype=bool)
        on_grid[grid.idx] = True
        for c, co in zip(self.constraints, self.coeffs, strict=True):
            if c.equality or co.k.size == 0:
                continue
            kin = co.k[on_grid[co.k]]
            mask[co.k if kin.size < 2 else co.k[(co.k < kin[0]) | (co.k > kin[-1])]] = True
        return mask

    def decode(self, ids: Ids) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
        """Constraint, row and sample position of each id."""
        ci = np.searchsorted(self.offset, ids, side="right") - 1
        kk = np.diff(self.k_start)[ci]
        local = ids - self.offset[ci]
        return ci, local // kk, local % kk

    def rows(self, ids: Ids) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``G`` (len(ids), N*n) and ``h`` for the given ids, in order (built by the dual active-set core)."""
        aff = self.aff
        ids = np.ascontiguousarray(ids, dtype=np.int64)
        g, h = np.empty((ids.size, aff.n_weights)), np.empty(ids.size)
        if ids.size:
            core().gi_rows(self._core_arrays(), ids, g, h)
        return g, h

    def _core_arrays(self) -> PoolArrays:
        """The arrays the core reads, with their dimensions (kept on the pool; refills write in place)."""
        if self._arrays is None:
            aff = self.aff
            keep = {k: np.ascontiguousarray(getattr(aff, k), dtype=np.float64)
                    for k in ("Gx", "Gv", "x_free", "v_free", "M")}
            self._arrays = PoolArrays(
                self.neg_bound, self.a_pos, self.a_vel, self.series_of, self.sample_of, keep["Gx"], keep["Gv"],
                keep["x_free"], keep["v_free"], keep["M"], self.vel_from,
            )
        return self._arrays

    def equality_rows(self) -> tuple[NDArray[np.float64], NDArray[np.float64], list[str]]:
        """Every equality row ``A w = b`` and its family (kept across refills unless an equality
        constraint is linearised)."""
        if self._eq is None or any(c.equality and c.linearised for c in self.constraints):
            self._eq = self._equality_rows()
        return self._eq

    def _equality_rows(self) -> tuple[NDArray[np.float64], NDArray[np.float64], list[str]]:
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
        out = [np.zeros(0, dtype=np.intp)]
        for ci, (c, co) in enumerate(zip(self.constraints, self.coeffs, strict=True)):
            if c.equality or co.k.size == 0:
                continue
            kk, m = co.k.size, co.bound.shape[1]
            p = np.unique(np.append(np.arange(0, kk, stride), kk - 1))
            out.append(self.offset[ci] + np.repeat(np.arange(m), p.size) * kk + np.tile(p, m))
        return np.concatenate(out)
