"""Exact solver for the whitened fit: Goldfarb-Idnani dual active-set method with ``P = I``.

Solves ``min 0.5 |z - z_c|^2  s.t.  E z = f,  G z <= h`` exactly (to round-off), where the rows of
``G`` are revealed incrementally: the method keeps the optimum of the constraints it has taken so
far (a dual-feasible point), adds the most violated candidate row with a step that keeps the
multipliers non-negative (dropping rows whose multiplier reaches zero), and asks an oracle for
more rows when every candidate holds. New rows never invalidate the current point, so cutting
planes from the dense grid slot straight in. The active rows' normals are kept as a QR
factorisation updated in O(n^2) per change (scipy's ``qr_insert``/``qr_delete``). A row that can
be neither reached nor made room for proves the problem infeasible (Goldfarb & Idnani 1983).

Reference: D. Goldfarb, A. Idnani, "A numerically stable dual method for solving strictly convex
quadratic programs", Math. Programming 27 (1983) 1-33.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

RowSource = Callable[[NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64]]]
"""``oracle(z) -> (G_new, h_new)``: rows violated at ``z`` that the candidates lack (empty if none)."""


class DualInfeasible(Exception):
    """The rows are inconsistent; ``rows`` lists the candidate rows involved, ``equalities`` whether
    the equality rows take part."""

    def __init__(self, rows: list[int], equalities: bool) -> None:
        self.rows, self.equalities = rows, equalities
        super().__init__(f"inconsistent rows {rows}")


@dataclass
class DualActiveSet:
    """Solver state. ``G``/``h``: candidate inequality rows (normalised); ``active``: indices of
    active candidate rows in factorisation order after the ``n_eq`` equality rows."""

    z_c: NDArray[np.float64]
    G: NDArray[np.float64]
    h: NDArray[np.float64]
    z: NDArray[np.float64] = field(init=False)
    active: list[int] = field(default_factory=list)
    u: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    n_eq: int = 0
    iterations: int = 0
    tol: float = 1e-13

    def __post_init__(self) -> None:
        n = self.z_c.size
        self.z = self.z_c.copy()
        self.Q = np.eye(n)
        self.R = np.zeros((n, 0))

    # ---------------------------------------------------------------- factorisation
    @property
    def q(self) -> int:
        return self.R.shape[1]

    def _directions(self, n_p: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Primal step ``d = (I - N N^+) n_p`` and dual step ``r = N^+ n_p``."""
        qt = self.Q.T @ n_p
        q = self.q
        d = self.Q[:, q:] @ qt[q:]
        r = scipy.linalg.solve_triangular(self.R[:q, :q], qt[:q]) if q else np.zeros(0)
        return d, r

    def _insert(self, n_p: NDArray[np.float64]) -> None:
        if self.q == 0:
            self.Q, self.R = scipy.linalg.qr(n_p[:, None])
        else:
            self.Q, self.R = scipy.linalg.qr_insert(self.Q, self.R, n_p, self.q, which="col")

    def _delete(self, pos: int) -> None:
        self.Q, self.R = scipy.linalg.qr_delete(self.Q, self.R, pos, which="col")

    # ---------------------------------------------------------------- constraints
    def add_equalities(self, e: NDArray[np.float64], f: NDArray[np.float64]) -> None:
        """Take the equality rows ``e z = f`` (before any inequality)."""
        for i in range(f.size):
            n_p = e[i]
            d, r = self._directions(n_p)
            s = n_p @ self.z - f[i]
            dn = d @ n_p
            if dn <= 1e-12 * (n_p @ n_p):
                if abs(s) > 1e-9:
                    raise DualInfeasible([], equalities=True)
                continue  # dependent and consistent: redundant
            t = -s / dn
            self.z = self.z + t * d
            self.u = np.append(self.u - t * r, t)
            self._insert(n_p)
            self.n_eq += 1

    def add_rows(self, g: NDArray[np.float64], h: NDArray[np.float64]) -> None:
        """Append candidate inequality rows ``g z <= h``."""
        if h.size:
            self.G = np.vstack([self.G, g])
            self.h = np.concatenate([self.h, h])

    def _add(self, p: int) -> None:
        """Make candidate row ``p`` active (GI steps 2-3)."""
        n_p = -self.G[p]  # GI convention: n_p . z >= b_p
        b_p = -self.h[p]
        u_p = 0.0
        while True:
            self.iterations += 1
            d, r = self._directions(n_p)
            s = n_p @ self.z - b_p
            ineq = r[self.n_eq :]
            cand = np.flatnonzero(ineq > 1e-14)
            t1, k = np.inf, -1
            if cand.size:
                ratios = self.u[self.n_eq :][cand] / ineq[cand]
                j = int(np.argmin(ratios))
                t1, k = float(ratios[j]), int(cand[j])
            dn = d @ n_p
            t2 = np.inf if dn <= 1e-12 * (n_p @ n_p) else -s / dn
            if not np.isfinite(t1) and not np.isfinite(t2):
                involved = [self.active[i] for i in np.flatnonzero(ineq < -1e-14)] + [p]
                raise DualInfeasible(involved, equalities=bool(np.any(np.abs(r[: self.n_eq]) > 1e-14)))
            t = min(t1, t2)
            self.z = self.z + (t * d if np.isfinite(t2) else 0.0)
            self.u = self.u - t * r
            u_p += t
            if t == t2:
                self.u = np.append(self.u, u_p)
                self._insert(n_p)
                self.active.append(p)
                return
            # drop the k-th active inequality: its multiplier reached zero
            self._delete(self.n_eq + k)
            self.u = np.delete(self.u, self.n_eq + k)
            del self.active[k]

    def solve(self, oracle: RowSource, max_iter: int = 10_000) -> NDArray[np.float64]:
        """Iterate until no candidate and no oracle row is violated; returns ``z``."""
        while self.iterations < max_iter:
            s = self.G @ self.z - self.h if self.h.size else np.zeros(0)
            if s.size and s.max() > self.tol:
                self._add(int(np.argmax(s)))
                continue
            g_new, h_new = oracle(self.z)
            if h_new.size == 0:
                return self.z
            self.add_rows(g_new, h_new)
        raise RuntimeError("dual active-set method: iteration limit reached")
