"""Calling QP backends through qpsolvers: name check, sparse/dense input, wrapped failures.

No hand-written solver switch: the backend name is passed through to qpsolvers, which dispatches.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import qpsolvers
import scipy.sparse as sp
from numpy.typing import NDArray

from tooltransfer.errors import SolverError, UnknownSolverError

DEFAULT_OPTIONS: dict[str, dict[str, Any]] = {
    # plain OSQP calls ("full" strategy); the cutting-plane seed uses its own (tooltransfer.dmp.qp.solve.SEED_OPTIONS)
    "osqp": {"eps_abs": 1e-7, "eps_rel": 1e-7, "max_iter": 20000, "polishing": True, "verbose": False},
    "clarabel": {"verbose": False},
}


def check_solver(name: str) -> str:
    """Return ``name`` if qpsolvers has that backend installed, else raise :class:`UnknownSolverError`."""
    if name not in qpsolvers.available_solvers:
        raise UnknownSolverError(name, qpsolvers.available_solvers)
    return name


@dataclass(frozen=True)
class QPOutcome:
    """One backend call: primal ``x`` (None when unusable), inequality duals ``z``, status.

    ``found`` is the backend's own verdict; ``x`` is also kept when the backend stopped without
    converging (the caller measures and reports the true violation).
    """

    x: NDArray[np.float64] | None
    z: NDArray[np.float64] | None
    found: bool
    infeasible: bool
    status: str
    iterations: int | None
    seconds: float


def _iterations(extras: dict[str, Any]) -> int | None:
    info = extras.get("info")
    if info is not None and hasattr(info, "iter"):
        return int(info.iter)
    its = extras.get("iterations")
    if its is not None:
        return int(np.atleast_1d(its)[0])
    return None


def _status(solver: str, found: bool, extras: dict[str, Any]) -> tuple[str, bool]:
    """Backend status text and whether it certifies primal infeasibility."""
    if found:
        return "solved", False
    if solver == "quadprog":  # quadprog's dual active-set method fails only on inconsistent rows
        return "constraints are inconsistent", True
    info = extras.get("info")
    status = str(getattr(info, "status", extras.get("status", "failed")))
    low = status.lower().replace("_", " ")
    return status, ("primal infeasible" in low or "primalinfeasible" in low)


def _dense_csc(m: NDArray[np.float64]) -> sp.csc_matrix:
    """The dense array ``m`` as a CSC matrix keeping every entry (zeros too: the rows here are
    dense), built from its column-major values directly (scipy's generic conversion goes through
    COO, a large part of a small QP's time)."""
    a = np.asarray(m, dtype=np.float64)
    r, c = a.shape
    return sp.csc_matrix(
        (a.ravel(order="F"), np.tile(np.arange(r, dtype=np.int32), c), np.arange(0, r * c + 1, r, dtype=np.int32)),
        shape=(r, c),
    )


def solve_qp(
    P: NDArray[np.float64],
    q: NDArray[np.float64],
    G: NDArray[np.float64] | None,
    h: NDArray[np.float64] | None,
    A: NDArray[np.float64] | None,
    b: NDArray[np.float64] | None,
    solver: str,
    initvals: NDArray[np.float64] | None = None,
    options: dict[str, Any] | None = None,
) -> QPOutcome:
    """Solve ``min 0.5 x'Px + q'x  s.t.  Gx <= h, Ax = b`` with a qpsolvers backend.

    Backend exceptions are wrapped in :class:`SolverError`; warnings are silenced (the caller
    measures the true violation itself).
    """
    opts = {**DEFAULT_OPTIONS.get(solver, {}), **(options or {})}
    sparse = solver in qpsolvers.sparse_solvers and solver not in qpsolvers.dense_solvers

    def conv(m: NDArray[np.float64] | None) -> Any:
        if m is None or m.shape[0] == 0:
            return None
        return _dense_csc(m) if sparse else m

    problem = qpsolvers.Problem(
        conv(P),
        q,
        conv(G),
        None if G is None or G.shape[0] == 0 else h,
        conv(A),
        None if A is None or A.shape[0] == 0 else b,
    )
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sol = qpsolvers.solve_problem(problem, solver=solver, initvals=initvals, **opts)
    except Exception as exc:  # wrapped: users never see a backend's internals
        msg = str(exc)
        seconds = time.perf_counter() - start
        if "inconsistent" in msg or "infeasible" in msg.lower():
            return QPOutcome(None, None, False, True, msg, None, seconds)
        raise SolverError(solver, msg) from exc
    seconds = time.perf_counter() - start
    extras = sol.extras or {}
    status, infeasible = _status(solver, bool(sol.found), extras)
    # a non-converged answer is kept: the caller measures its true violation and reports it
    usable = not infeasible and sol.x is not None and bool(np.all(np.isfinite(sol.x)))
    x = sol.x if usable else None
    return QPOutcome(x, sol.z if usable else None, bool(sol.found), infeasible, status, _iterations(extras), seconds)
