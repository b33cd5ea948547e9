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
by the path at isolated instants), so the method takes hundreds of cheap steps, and interpreter
overhead per step was the cost (about 100 us in NumPy against a few us compiled).

A warm start (:meth:`DualActiveSet.warm_start`) takes a guess of the active rows at once and drops
those with negative multipliers, which gives the dual-feasible start the method needs; the
constrained fit uses it across re-linearisations.

Reference: D. Goldfarb, A. Idnani, "A numerically stable dual method for solving strictly convex
quadratic programs", Math. Programming 27 (1983) 1-33.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from dmp.qp.native import addr, core

RowSource = Callable[[NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64]]]
"""``oracle(z) -> (G_new, h_new)``: rows violated at ``z`` that the candidates lack (empty if none)."""

_NEED_ROWS, _INFEASIBLE, _MAX_ITER = 0, -1, -2


class DualInfeasible(Exception):
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
    """

    def __init__(self, z_c: NDArray[np.float64], g: NDArray[np.float64], h: NDArray[np.float64], tol: float = 1e-13):
        n = z_c.size
        self.n, self.tol = n, tol
        self.z = np.array(z_c, dtype=np.float64)
        self._zc = self.z.copy()
        self.G = np.ascontiguousarray(g, dtype=np.float64).reshape(-1, n)
        self.h = np.ascontiguousarray(h, dtype=np.float64).ravel()
        self._Q = np.asfortranarray(np.eye(n))
        self._R = np.zeros((n, n), order="F")
        self._u = np.zeros(n + 1)
        self._active = np.zeros(n + 1, dtype=np.int32)
        self._q = ctypes.c_int(0)
        self.n_eq = 0
        self._iters = ctypes.c_int(0)
        self._work = np.zeros(4 * n)
        self._info = np.zeros(n + 2, dtype=np.int32)
        self._p = {
            "Q": addr(self._Q, np.float64, True), "R": addr(self._R, np.float64, True),
            "u": addr(self._u, np.float64), "active": addr(self._active, np.int32),
            "z": addr(self.z, np.float64), "work": addr(self._work, np.float64),
            "info": addr(self._info, np.int32),
        }

    @property
    def iterations(self) -> int:
        return self._iters.value

    @property
    def active(self) -> list[int]:
        return self._active[: self._q.value - self.n_eq].tolist()

    def add_equalities(self, e: NDArray[np.float64], f: NDArray[np.float64]) -> None:
        """Take the equality rows ``e z = f`` (before any inequality); dependent consistent rows
        are skipped, dependent inconsistent ones raise :class:`DualInfeasible`."""
        lib, p = core(), self._p
        e = np.ascontiguousarray(e, dtype=np.float64).reshape(-1, self.n)
        for i in range(f.size):
            code = lib.gi_equality(
                self.n, p["Q"], p["R"], p["u"], ctypes.byref(self._q), p["z"], addr(e[i], np.float64),
                float(f[i]), p["work"],
            )
            if code < 0:
                raise DualInfeasible([], equalities=True)
            self.n_eq += code == 0

    def warm_start(self, rows: NDArray[np.intp]) -> int:
        """Take the candidate rows ``rows`` (indices into ``G``, a guess of the active set) as active,
        then drop those with negative multipliers until the point is dual feasible; call after
        :meth:`add_equalities` and before :meth:`solve`. Returns the number of rows kept."""
        idx = np.ascontiguousarray(rows, dtype=np.int32)
        if idx.size == 0:
            return 0
        if idx.min() < 0 or idx.max() >= self.h.size:
            raise IndexError("warm start rows out of range")
        p = self._p
        return int(core().gi_warm(
            self.n, addr(self.G, np.float64), addr(self.h, np.float64), p["Q"], p["R"], p["u"], p["active"],
            ctypes.byref(self._q), self.n_eq, p["z"], addr(self._zc, np.float64), addr(idx, np.int32), idx.size,
            p["work"],
        ))

    def add_rows(self, g: NDArray[np.float64], h: NDArray[np.float64]) -> None:
        """Append candidate inequality rows ``g z <= h``."""
        if h.size:
            self.G = np.ascontiguousarray(np.vstack([self.G, g]))
            self.h = np.concatenate([self.h, h])

    def solve(self, oracle: RowSource, max_iter: int = 10_000) -> NDArray[np.float64]:
        """Iterate until no candidate and no oracle row is violated; returns ``z``."""
        lib, p, info = core(), self._p, self._info
        ninfo, eq_involved = ctypes.c_int(0), ctypes.c_int(0)
        while True:
            code = lib.gi_solve(
                self.n, self.h.size, addr(self.G, np.float64), addr(self.h, np.float64), p["Q"], p["R"], p["u"],
                p["active"], ctypes.byref(self._q), self.n_eq, p["z"], self.tol, max_iter,
                ctypes.byref(self._iters), p["info"], ctypes.byref(ninfo), ctypes.byref(eq_involved), p["work"],
            )
            if code == _INFEASIBLE:
                raise DualInfeasible(info[: ninfo.value].tolist(), equalities=bool(eq_involved.value))
            if code == _MAX_ITER:
                raise RuntimeError("dual active-set method: iteration limit reached")
            g_new, h_new = oracle(self.z)
            if h_new.size == 0:
                return self.z
            self.add_rows(g_new, h_new)
