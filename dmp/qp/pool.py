"""Candidate constraint rows on the dense grid, built lazily (for the cutting-plane solver)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from dmp.affine import AffineRollout
from dmp.qp.constraints.base import Coefficients, Constraint

Key = tuple[int, int, int]
"""(constraint index, sample position within its coefficients, row index)."""


@dataclass
class RowPool:
    """Every row of every constraint at every dense sample, for one linearisation path.

    Rows are only materialised for the keys asked for; residuals of all of them come from one
    rollout of the dense grid.
    """

    constraints: Sequence[Constraint]
    coeffs: list[Coefficients]
    aff: AffineRollout

    @classmethod
    def build(cls, constraints: Sequence[Constraint], aff: AffineRollout, x_lin: NDArray[np.float64]) -> RowPool:
        return cls(constraints, [c.coefficients(aff.t, x_lin) for c in constraints], aff)

    def residuals(
        self, w: NDArray[np.float64], samples: NDArray[np.bool_] | None = None
    ) -> list[NDArray[np.float64]]:
        """Residuals (K_c, m_c) of every inequality constraint for flat weights ``w`` (<= 0 is satisfied).

        With a mask ``samples`` (T,) only those samples are evaluated (the rest read ``-inf``).
        Equality constraints, which the exact step holds as equalities, are not evaluated (``-inf``).
        """
        if samples is None:
            x, v = self.aff.positions(w), self.aff.velocities(w)
            return [
                np.full(co.bound.shape, -np.inf) if c.equality else co.residuals(x, v)
                for c, co in zip(self.constraints, self.coeffs, strict=True)
            ]
        idx = np.flatnonzero(samples)
        wm = np.asarray(w).reshape(-1, self.aff.n_dims) @ self.aff.M.T
        xs = self.aff.x_free[idx] + self.aff.Gx[idx] @ wm
        vs = self.aff.v_free[idx] + self.aff.Gv[idx] @ wm
        where = np.cumsum(samples) - 1  # row of each masked sample in xs, vs
        out = []
        for c, co in zip(self.constraints, self.coeffs, strict=True):
            r = np.full(co.bound.shape, -np.inf)
            sel = np.flatnonzero(samples[co.k]) if not c.equality else np.zeros(0, dtype=np.intp)
            if sel.size:
                r[sel] = co.residuals_at(sel, xs[where[co.k[sel]]], vs[where[co.k[sel]]])
            out.append(r)
        return out

    def suspects(self, coarse: RowPool, res: list[NDArray[np.float64]], tol: float, factor: int) -> NDArray[np.bool_]:
        """Samples of this (dense) pool that may violate a row, judged from the residuals ``res`` of
        the same rows on ``coarse``, whose sample i is this pool's sample ``factor * i``.

        A stretch between two coarse samples is suspect when its larger end residual plus half the
        second differences there (four times the interpolation-error estimate of a smooth residual)
        exceeds ``tol``; samples outside the coarse ones of a constraint are always suspects. Only a
        filter: the caller confirms with a full pass.
        """
        mask = np.zeros(self.aff.t.size, dtype=bool)
        for c, co_c, co_d, r in zip(self.constraints, coarse.coeffs, self.coeffs, res, strict=True):
            if c.equality or co_d.k.size == 0:
                continue
            if co_c.k.size < 2:
                mask[co_d.k] = True
                continue
            d2 = np.zeros_like(r)
            d2[1:-1] = np.abs(r[:-2] - 2.0 * r[1:-1] + r[2:])
            top = (r + 0.5 * d2).max(axis=1)
            bad = np.flatnonzero(np.maximum(top[:-1], top[1:]) > tol)
            lo, hi = factor * co_c.k[bad], factor * co_c.k[bad + 1]
            cover = np.zeros(mask.size + 1, dtype=np.int64)
            np.add.at(cover, lo, 1)
            np.add.at(cover, hi + 1, -1)
            mask |= np.cumsum(cover[:-1]) > 0
            edge = (co_d.k < factor * co_c.k[0]) | (co_d.k > factor * co_c.k[-1])
            mask[co_d.k[edge]] = True
        return mask

    def equality_keys(self) -> list[Key]:
        keys: list[Key] = []
        for ci, (c, co) in enumerate(zip(self.constraints, self.coeffs, strict=True)):
            if c.equality:
                keys += [(ci, k, j) for k in range(co.k.size) for j in range(co.bound.shape[1])]
        return keys

    def map_keys(self, keys: list[Key], other: RowPool) -> list[Key]:
        """The same (constraint, time, row) triples as ``keys`` of pool ``other``, in this pool."""
        if not keys:
            return []
        arr = np.asarray(keys)
        out: list[Key] = []
        for ci in np.unique(arr[:, 0]).tolist():
            sel = arr[arr[:, 0] == ci]
            t = other.aff.t[other.coeffs[ci].k[sel[:, 1]]]
            tk = self.aff.t[self.coeffs[ci].k]
            pos = np.clip(np.searchsorted(tk, t), 0, tk.size - 1)
            hit = np.abs(tk[pos] - t) <= 1e-12 * np.maximum(1.0, np.abs(t))
            out += [(ci, p, j) for p, j in zip(pos[hit].tolist(), sel[hit, 2].tolist(), strict=True)]
        return out

    def coarse_keys(self, stride: int) -> list[Key]:
        """Every inequality row at every ``stride``-th applicable sample (and the last one)."""
        keys: list[Key] = []
        for ci, (c, co) in enumerate(zip(self.constraints, self.coeffs, strict=True)):
            if c.equality or co.k.size == 0:
                continue
            pos = np.unique(np.append(np.arange(0, co.k.size, stride), co.k.size - 1))
            keys += [(ci, int(k), j) for k in pos for j in range(co.bound.shape[1])]
        return keys

    def rows(self, keys: Sequence[Key]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``G`` (len(keys), N*n) and ``h`` for the given keys, in key order."""
        nw = self.aff.n_weights
        if not keys:
            return np.zeros((0, nw)), np.zeros(0)
        arr = np.asarray(keys)
        g, h = np.zeros((arr.shape[0], nw)), np.zeros(arr.shape[0])
        for ci in np.unique(arr[:, 0]):
            sel = np.flatnonzero(arr[:, 0] == ci)
            rows = self.coeffs[ci].rows(self.aff, arr[sel, 1], arr[sel, 2])
            g[sel], h[sel] = rows.G, rows.h
        return g, h

    def family(self, key: Key) -> str:
        return self.constraints[key[0]].family

    def peaks(self, res: list[NDArray[np.float64]], threshold: float, exclude: set[Key], limit: int = 64) -> list[Key]:
        """Keys of local maxima in time of violated inequality rows (> ``threshold``), not in ``exclude``.

        One row per violated stretch keeps the working set small and its rows well separated; at
        most ``limit`` per (constraint, row), the worst first.
        """
        out: list[Key] = []
        for ci, (c, r) in enumerate(zip(self.constraints, res, strict=True)):
            if c.equality or r.size == 0:
                continue
            peak = r > threshold
            peak[1:] &= r[1:] >= r[:-1]
            peak[:-1] &= r[:-1] >= r[1:]
            kk, jj = np.nonzero(peak)
            if kk.size > limit:  # keep the worst ``limit`` of each row j
                order = np.lexsort((-r[kk, jj], jj))
                kk, jj = kk[order], jj[order]
                rank = np.arange(kk.size) - np.searchsorted(jj, jj)
                kk, jj = kk[rank < limit], jj[rank < limit]
            out += [key for key in zip([ci] * kk.size, kk.tolist(), jj.tolist(), strict=True) if key not in exclude]
        return out

    def most_violated(self, res: list[NDArray[np.float64]]) -> tuple[Key | None, float]:
        """The inequality row with the largest residual, and that residual."""
        best: Key | None = None
        val = -np.inf
        for ci, (c, r) in enumerate(zip(self.constraints, res, strict=True)):
            if c.equality or r.size == 0:
                continue
            k, j = np.unravel_index(int(np.argmax(r)), r.shape)
            if r[k, j] > val:
                best, val = (ci, int(k), int(j)), float(r[k, j])
        return best, val
