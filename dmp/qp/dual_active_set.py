"""Exact solver for the whitened fit: Goldfarb-Idnani dual active-set method with ``P = I``.

Solves ``min 0.5 |z - z_c|^2  s.t.  E z = f,  G z <= h`` exactly (to round-off), where the rows of
``G`` are revealed incrementally: the method keeps the optimum of the constraints it has taken so
far (a dual-feasible point), adds the most violated candidate row with a step that keeps the
multipliers non-negative (dropping rows whose multiplier reaches zero), and asks an oracle for
more rows when every candidate holds. New rows never invalidate the current point, so cutting
planes from the dense grid slot straight in. The active rows' normals are kept as a QR
factorisation updated by Givens rotations in O(n^2) per change. A row that can be neither
reached nor made room for proves the problem infeasible (Goldfarb & Idnani 1983).

The add/drop steps run in a small C core (``_gi_core.c``, built with the package and called
through ctypes): the DMP fits are degenerate (constraints active along stretches of time, touched
by the path at isolated instants), so the method takes hundreds of cheap steps, and in NumPy the
interpreter overhead of each step costs far more than its arithmetic. Without the
compiled core (an install without a C compiler, or ``TOOLTRANSFER_NO_NATIVE=1``) the same steps run
in NumPy (:mod:`tooltransfer.dmp.qp._gi_numpy`, chosen by :func:`tooltransfer.dmp.qp.native.core`), to the same optimum.

A warm start (:meth:`DualActiveSet.warm_start`) takes a guess of the active rows at once and drops
those with negative multipliers, which gives the dual-feasible start the method needs; the
constrained fit uses it across re-linearisations.

Reference: D. Goldfarb, A. Idnani, "A numerically stable dual method for solving strictly convex
quadratic programs", Math. Programming 27 (1983) 1-33.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.qp.gi_state import INFEASIBLE, MAX_ITER, GIWork
from tooltransfer.dmp.qp.native import core
from tooltransfer.errors import ToolTransferError

RowSource = Callable[[NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64]]]
"""``oracle(z) -> (G_new, h_new)``: rows violated at ``z`` that the candidates lack (empty if none)."""


class DualInfeasible(ToolTransferError):
    """The rows are inconsistent; ``rows`` lists the candidate rows involved, ``equalities`` whether
    the equality rows take part."""

    def __init__(self, rows: list[int], equalities: bool) -> None:
        self.rows, self.equalities = rows, equalities
        super().__init__(f"inconsistent rows {rows}")


class DualActiveSet:
    """Solver state for ``n`` whitened variables.

    Attributes:
        z: current point (n,): the optimum over the rows taken so far.
        G, h: candidate inequality rows (m, n) and (m,), normalised by the caller.
        active: candidate indices of the active inequality rows.
        iterations: add/drop steps taken.
        core: the dual active-set core the steps run in (:func:`tooltransfer.dmp.qp.native.core` at creation).
    """

    def __init__(self, z_c: NDArray[np.float64], g: NDArray[np.float64], h: NDArray[np.float64], tol: float = 1e-13):
        self._w = w = GIWork(z_c)
        self.n, self.tol = w.n, tol
        self.z = w.z
        self.G = np.ascontiguousarray(g, dtype=np.float64).reshape(-1, w.n)
        self.h = np.ascontiguousarray(h, dtype=np.float64).ravel()
        self.core = core()

    @property
    def n_eq(self) -> int:
        return self._w.n_eq

    @property
    def iterations(self) -> int:
        return self._w.iters.value

    @property
    def active(self) -> list[int]:
        w = self._w
        return w.active[: w.q.value - w.n_eq].tolist()

    def add_equalities(self, e: NDArray[np.float64], f: NDArray[np.float64]) -> None:
        """Take the equality rows ``e z = f`` (before any inequality); dependent consistent rows
        are skipped, dependent inconsistent ones raise :class:`DualInfeasible`."""
        w = self._w
        if w.q.value != w.n_eq:
            raise RuntimeError("equality rows must be taken before any inequality")
        e = np.ascontiguousarray(e, dtype=np.float64).reshape(-1, self.n)
        f = np.asarray(f, dtype=np.float64).ravel()
        for i in range(f.size):
            code = self.core.gi_equality(w, e[i], float(f[i]))
            if code < 0:
                raise DualInfeasible([], equalities=True)
            w.n_eq += code == 0

    def warm_start(self, rows: NDArray[np.intp]) -> int:
        """Take the candidate rows ``rows`` (indices into ``G``, a guess of the active set) as active,
        then drop those with negative multipliers until the point is dual feasible; call after
        :meth:`add_equalities` and before :meth:`solve`. Returns the number of rows kept."""
        idx = np.ascontiguousarray(rows, dtype=np.int32).ravel()
        if idx.size == 0:
            return 0
        if idx.min() < 0 or idx.max() >= self.h.size:
            raise IndexError("warm start rows out of range")
        return self.core.gi_warm(self._w, self.G, self.h, idx)

    def add_rows(self, g: NDArray[np.float64], h: NDArray[np.float64]) -> None:
        """Append candidate inequality rows ``g z <= h``."""
        if h.size:
            self.G = np.ascontiguousarray(np.vstack([self.G, g]), dtype=np.float64)
            self.h = np.ascontiguousarray(np.concatenate([self.h, h]), dtype=np.float64)

    def solve(self, oracle: RowSource, max_iter: int = 10_000) -> NDArray[np.float64]:
        """Iterate until no candidate and no oracle row is violated; returns ``z``."""
        while True:
            code, rows, eq = self.core.gi_solve(self._w, self.G, self.h, self.tol, max_iter)
            if code == INFEASIBLE:
                raise DualInfeasible(rows, equalities=eq)
            if code == MAX_ITER:
                raise RuntimeError("dual active-set method: iteration limit reached")
            g_new, h_new = oracle(self.z)
            if h_new.size == 0:
                return self.z
            self.add_rows(g_new, h_new)
