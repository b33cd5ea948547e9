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

    def residuals(self, w: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        """Residuals (K_c, m_c) of every constraint for flat weights ``w`` (<= 0 is satisfied)."""
        x, v = self.aff.positions(w), self.aff.velocities(w)
        return [c.residuals(x, v) for c in self.coeffs]

    def equality_keys(self) -> list[Key]:
        keys: list[Key] = []
        for ci, (c, co) in enumerate(zip(self.constraints, self.coeffs, strict=True)):
            if c.equality:
                keys += [(ci, k, j) for k in range(co.k.size) for j in range(co.bound.shape[1])]
        return keys

    def map_keys(self, keys: list[Key], other: RowPool) -> list[Key]:
        """The same (constraint, time, row) triples as ``keys`` of pool ``other``, in this pool."""
        out: list[Key] = []
        for ci, kpos, j in keys:
            t = other.aff.t[other.coeffs[ci].k[kpos]]
            kk = self.coeffs[ci].k
            pos = int(np.clip(np.searchsorted(self.aff.t[kk], t), 0, kk.size - 1))
            if abs(self.aff.t[kk[pos]] - t) <= 1e-12 * max(1.0, abs(t)):
                out.append((ci, pos, j))
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

    def peaks(self, res: list[NDArray[np.float64]], threshold: float, exclude: set[Key], limit: int = 16) -> list[Key]:
        """Keys of local maxima in time of violated inequality rows (> ``threshold``), not in ``exclude``.

        One row per violated stretch keeps the working set small and its rows well separated.
        """
        out: list[Key] = []
        for ci, (c, r) in enumerate(zip(self.constraints, res, strict=True)):
            if c.equality or r.size == 0:
                continue
            for j in range(r.shape[1]):
                col = r[:, j]
                left = np.concatenate([[-np.inf], col[:-1]])
                right = np.concatenate([col[1:], [-np.inf]])
                cand = np.flatnonzero((col > threshold) & (col >= left) & (col >= right))
                cand = cand[np.argsort(-col[cand])][:limit]
                out += [(ci, int(k), j) for k in cand if (ci, int(k), j) not in exclude]
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
