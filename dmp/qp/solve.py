"""Solving the constrained DMP fit (docs/design.md section 4).

Strategy ``"cutting_planes"`` (default), the fast and exact way:

1. whiten: with ``P = L L'`` and ``w = L^{-T} z`` the objective becomes ``0.5 |z - z_c|^2``
   (the trajectory-space Hessian is badly conditioned; its whitened form is the identity);
2. rows are normalised and taken lazily: the exact step (:mod:`tooltransfer.dmp.qp.dual_active_set`, a
   Goldfarb-Idnani dual active-set method in C) starts from the unconstrained optimum and takes
   the peaks of every violated stretch (:mod:`tooltransfer.dmp.qp.pool`, scanned in C), first on the
   constraint grid, then on the dense samples the grid residuals point at, then on every dense
   sample, until no dense row is violated: the result is the exact optimum over all dense rows,
   and a row the method cannot take proves infeasibility and names the families involved
   (without the compiled core both run in NumPy, :mod:`tooltransfer.dmp.qp.native`: the same optimum, more
   slowly; ``benchmarks/bench_dmp.py`` compares the two);
3. non-convex rows (discs) are re-linearised at the solution and step 2 repeated (sequential
   convex programming) until the path moves less than ``scp_tol``; each repetition starts from
   the previous active rows (warm start: taken at once, rows with negative multipliers dropped)
   with the previous candidates, so it needs far fewer oracle rounds than a cold start.

The cost is in the oracle rounds (a compiled scan of the dense residuals plus building the new
rows) and the add/drop steps of the exact method; ``benchmarks/bench_dmp.py`` measures both
(figures in ``benchmarks/README.md``).

The default path runs the backend first (``seed_with_backend=True``): OSQP solves, at eps 1e-3
without polishing, the whitened QP over the rows of a coarse subset (one sample per basis
function) that the unconstrained optimum violates, and the rows it finds active are the exact
step's first candidates. OSQP's answer is never returned as such: the exact step finishes, so
the seed changes the cost, not the optimum; ``seed_with_backend=False`` skips it (the seed's cost
is mostly the Python side of qpsolvers and osqp, ``benchmarks/README.md``). Taking OSQP's active
rows as a warm-start guess of the active set is not done: it made the active set's factorisation
ill-conditioned.

Strategy ``"full"`` is the plain condensed formulation: every row on the constraint grid at
once, weights as variables, one backend call per linearisation; kept as the reference peer.

Either way the true violation of every family is measured afterwards on the dense grid.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from tooltransfer.dmp.affine import AffineRollout
from tooltransfer.dmp.qp.backends import QPOutcome, check_solver, solve_qp
from tooltransfer.dmp.qp.dual_active_set import DualActiveSet, DualInfeasible
from tooltransfer.dmp.qp.pool import RowPool, Samples
from tooltransfer.dmp.qp.problem import FitProblem, stack_rows, unconstrained_weights
from tooltransfer.dmp.qp.result import FitResult
from tooltransfer.dmp.trajectory import Rollout
from tooltransfer.errors import InputError, SolverError, ToolTransferError
from tooltransfer.validation import check_array

Strategy = Literal["cutting_planes", "full"]


COARSE_PER_BASIS = 1
"""Default size of the seed's coarse grid: this many samples per basis function."""

SEED_OPTIONS: dict[str, Any] = {"eps_abs": 1e-3, "eps_rel": 1e-3, "polishing": False}
"""OSQP settings of the seed: a rough active set is all it is for (the exact step finishes)."""

SEED_DUAL_FRACTION = 1e-3
"""Seed rows whose multiplier exceeds this fraction of the largest become candidates."""


class _Infeasible(ToolTransferError):
    def __init__(self, families: tuple[str, ...], reason: str) -> None:
        self.families, self.reason = families, reason


class _Counter:
    def __init__(self) -> None:
        self.n_qp = 0
        self.iterations: int | None = 0
        self.finish = False
        self.n_exact = 0

    def add(self, out: QPOutcome) -> None:
        self.n_qp += 1
        if out.iterations is None or self.iterations is None:
            self.iterations = None
        else:
            self.iterations += out.iterations


def _whitening(p: NDArray[np.float64]) -> NDArray[np.float64]:
    """``T = L^{-T}`` with ``P + eps I = L L'``, so ``w = T z`` whitens the objective."""
    n = p.shape[0]
    reg = 1e-12 * max(float(np.trace(p)) / n, 1e-300)
    lower = scipy.linalg.cholesky(p + reg * np.eye(n), lower=True)
    return scipy.linalg.solve_triangular(lower, np.eye(n), lower=True).T


def _normalise(g: NDArray[np.float64], h: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    s = np.sqrt(np.einsum("ij,ij->i", g, g))
    s[s == 0.0] = 1.0
    return g / s[:, None], h / s


def _diagnose(families: list[str], solve_without: Any) -> _Infeasible:
    """Families whose removal alone restores feasibility (or all of them when none does)."""
    present = sorted(set(families))
    involved = tuple(f for f in present if solve_without(f))
    fams = involved or tuple(present)
    how = "removing any one of them restores feasibility" if involved else "no single family alone is to blame"
    return _Infeasible(fams, f"the constraints of families {', '.join(fams)} cannot hold together ({how})")


def _rows_w(
    pool: RowPool, ids: NDArray[np.intp], tw: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Rows of ``ids`` in whitened coordinates, normalised to unit length."""
    g, h = pool.rows(ids)
    return _normalise(g @ tw, h)


@dataclass
class _Levels:
    """The sample subsets the oracle looks at: the constraint grid, then all dense samples."""

    grid: Samples
    full: Samples
    factor: int
    outside: NDArray[np.bool_]
    """dense samples the grid says nothing about (see :meth:`RowPool.outside_grid`)."""


@dataclass(frozen=True)
class _WhitenedQP:
    """One linearisation's fit in whitened coordinates: minimise ``0.5 |z - z_c|^2`` subject to the
    rows of ``pool`` (taken in weight space, mapped by ``w = tw z``), scanned on ``levels``."""

    pool: RowPool
    levels: _Levels
    tw: NDArray[np.float64]
    z_c: NDArray[np.float64]


@dataclass(frozen=True)
class _ExactRun:
    """How the exact step runs: the backend (and its options) that seeds it, the accepted
    violation ``tol`` [m or m/s] of a dense row, the seed's coarse stride on the constraint grid and
    whether the backend seeds at all."""

    solver: str
    options: dict[str, Any] | None
    tol: float
    stride: int
    seed_with_backend: bool


def _seed(qp: _WhitenedQP, a_z: NDArray[np.float64], b_z: NDArray[np.float64], run: _ExactRun,
          cnt: _Counter) -> NDArray[np.intp]:
    """Candidate rows from the backend: it solves, at moderate accuracy, the whitened QP over the
    rows of a coarse subset (every ``run.stride * qp.levels.factor``-th dense sample) that the
    unconstrained optimum violates, with the normalised equality rows ``a_z z = b_z``; the rows it
    finds active (multiplier above ``SEED_DUAL_FRACTION`` of the largest) are returned."""
    pool, z_c = qp.pool, qp.z_c
    ids = pool.coarse_ids(run.stride * qp.levels.factor)
    g, h = _rows_w(pool, ids, qp.tw)
    keep = g @ z_c - h > 0.0
    if not keep.any():
        return np.zeros(0, dtype=np.intp)  # the unconstrained optimum meets the coarse rows
    ids, g, h = ids[keep], g[keep], h[keep]
    opts = dict(SEED_OPTIONS) if run.solver == "osqp" else {}
    out = solve_qp(np.eye(z_c.size), -z_c, g, h, a_z, b_z, run.solver, options={**opts, **(run.options or {})})
    cnt.add(out)
    if out.x is None or out.z is None or not np.any(out.z > 0):
        return ids  # infeasible or failed: the exact method decides, and explains
    return ids[out.z > SEED_DUAL_FRACTION * out.z.max()]


def _cutting_planes(
    qp: _WhitenedQP, run: _ExactRun, cnt: _Counter, seed: NDArray[np.intp] | None = None,
    extra: NDArray[np.intp] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.intp]]:
    """Exact optimum over every dense row, starting from the guessed active rows ``seed`` (plus
    candidates ``extra``); returns ``z``, the ids of the active rows and of every candidate."""
    pool, levels, tw, z_c, tol = qp.pool, qp.levels, qp.tw, qp.z_c, run.tol
    a, b, eq_fams = pool.equality_rows()
    a_z, b_z = _normalise(a @ tw, b)
    guess = np.unique(seed) if seed is not None else np.zeros(0, dtype=np.intp)
    cand = np.union1d(guess, extra) if extra is not None else guess
    if seed is None and run.seed_with_backend:  # the backend's active rows: candidates, not a guess
        cand = np.unique(_seed(qp, a_z, b_z, run, cnt))
    known = np.zeros(pool.size, dtype=bool)
    known[cand] = True
    chunks = [cand]
    state = DualActiveSet(z_c, *_rows_w(pool, cand, tw))

    def take(ids: NDArray[np.intp]) -> NDArray[np.intp]:
        ids = np.unique(ids)
        return ids[~known[ids]]

    def oracle(z: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        # the cheap grid first, then the dense samples the grid points at, then every dense sample
        w = tw @ z
        ids, res_g = pool.scan(w, levels.grid, tol, keep=True)
        new = take(ids)
        if not new.size and res_g is not None:
            sus = Samples.of(pool.aff, pool.suspects(res_g, levels.grid, tol, levels.outside))
            new = take(pool.scan(w, sus, tol)[0])
        if not new.size:
            new = take(pool.scan(w, levels.full, tol)[0])
        known[new] = True
        chunks.append(new)
        return _rows_w(pool, new, tw)

    try:
        state.add_equalities(a_z, b_z)
        if guess.size:
            state.warm_start(np.searchsorted(cand, guess))
        z = state.solve(oracle)
    except DualInfeasible as inf:
        ids = np.concatenate(chunks)
        if guess.size:  # a warm start can mislead the proof (near-dependent rows): prove it cold
            return _cutting_planes(qp, replace(run, seed_with_backend=False), cnt, None, ids)
        fams = pool.families(ids[np.asarray(inf.rows, dtype=np.intp)])
        if inf.equalities or not inf.rows:
            fams |= set(eq_fams)
        names = tuple(sorted(fams))
        raise _Infeasible(
            names, f"rows of families {', '.join(names)} admit no common solution "
            "(proved by the exact dual active-set method)",
        ) from None
    finally:
        cnt.n_exact += state.iterations
    cnt.finish = True
    every = np.concatenate(chunks)
    return z, every[np.asarray(state.active, dtype=np.intp)], every


def _full(
    problem: FitProblem, p: NDArray[np.float64], q: NDArray[np.float64], x_lin_dense: NDArray[np.float64],
    solver: str, options: dict[str, Any] | None, cnt: _Counter,
) -> NDArray[np.float64]:
    aff = problem.affine("grid")
    x_lin = x_lin_dense[:: problem.dense_factor]
    g, h, fam, a, b, efam = stack_rows(problem.constraints, aff, x_lin)
    out = solve_qp(p, q, g, h, a, b, solver, options=options)
    cnt.add(out)
    if out.infeasible:
        def without(f: str) -> bool:
            mi, me = fam != f, efam != f
            return solve_qp(p, q, g[mi], h[mi], a[me], b[me], solver, options=options).found

        fams = [*fam.tolist(), *efam.tolist()]
        raise _diagnose(fams, without)
    if out.x is None:
        raise SolverError(solver, f"no solution ({out.status})")
    return out.x


def _settled(problem: FitProblem, aff: AffineRollout, w: NDArray[np.float64], x: NDArray[np.float64],
             tol: float) -> dict[int, float] | None:
    """The true violations [m or m/s] of the linearised constraints that are not conservative (by their
    index in ``problem.constraints``) at ``w`` (positions ``x``), when each is within ``tol``; else None."""
    measured: dict[int, float] = {}
    v: NDArray[np.float64] | None = None
    for i, c in enumerate(problem.constraints):
        if c.linearised and not c.conservative:
            v = aff.velocities(w) if v is None else v
            measured[i] = c.violation(aff.t, x, v)
            if not measured[i] <= tol:  # NaN included
                return None
    return measured


def _dense_levels(problem: FitProblem, aff_d: AffineRollout, pool: RowPool) -> _Levels:
    """The oracle's sample subsets of the dense grid: the constraint grid (every ``dense_factor``-th
    sample), every sample, and the dense samples the grid says nothing about; built once per fit
    (the grids do not move with the linearisation)."""
    grid = Samples.of(aff_d, slice(0, None, problem.dense_factor))
    return _Levels(grid, Samples.of(aff_d, slice(None)), problem.dense_factor, pool.outside_grid(grid))


class _Relinearised:
    """The exact step across re-linearisations of one fit: each path rebuilds the row pool (reusing
    the previous pool's rows), and after the first the step warm-starts from the previous active
    rows with every row seen so far as candidates, so it takes a few oracle rounds instead of ~15."""

    def __init__(self, problem: FitProblem, aff_d: AffineRollout, tw: NDArray[np.float64],
                 z_c: NDArray[np.float64], run: _ExactRun, cnt: _Counter) -> None:
        self.problem, self.aff_d, self.tw, self.z_c, self.run, self.cnt = problem, aff_d, tw, z_c, run, cnt
        self.pool: RowPool | None = None
        self.levels: _Levels | None = None
        self.active = self.seen = np.zeros(0, dtype=np.intp)

    def step(self, x_lin: NDArray[np.float64], warm: bool) -> NDArray[np.float64]:
        """The exact optimum's weights with the rows linearised at the dense path ``x_lin`` [m]."""
        self.pool = RowPool.build(self.problem.constraints, self.aff_d, x_lin, previous=self.pool)
        if self.levels is None:
            self.levels = _dense_levels(self.problem, self.aff_d, self.pool)
        z, self.active, self.seen = _cutting_planes(
            _WhitenedQP(self.pool, self.levels, self.tw, self.z_c), self.run, self.cnt,
            self.active if warm else None, self.seen if warm else None,
        )
        return self.tw @ z


def _rollout(problem: FitProblem, aff_d: AffineRollout, w: NDArray[np.float64], x: NDArray[np.float64]) -> Rollout:
    """The fitted motion on the dense grid: positions ``x`` [m] (those of the weights ``w``),
    velocities [m/s] and the DMP's accelerations [m/s^2] (its transformation system with the
    forcing term of ``w``), so a caller gets the whole state without re-rolling the DMP."""
    dmp = problem.dmp
    wmat = w.reshape(dmp.n_basis, dmp.n_dims)
    v = aff_d.velocities(w)
    f = aff_d.psi @ wmat @ aff_d.M.T
    tau = float(problem.tau)  # type: ignore[arg-type]
    g = np.asarray(problem.g, dtype=np.float64)
    acc = np.asarray((dmp.alpha_z * (dmp.beta_z * (g - x) - tau * v) + f) / tau**2, dtype=np.float64)
    return Rollout(aff_d.t, x, v, acc)


def _dense_violations(problem: FitProblem, rollout: Rollout, measured: dict[int, float]) -> dict[str, float]:
    """The true violation [m or m/s] of every constraint family on the dense grid (the largest
    over its constraints): what the fit's status is judged by, whatever grid the solver saw.
    ``measured``: the violations of some constraints (by index) on this rollout already (:func:`_settled`)."""
    violations: dict[str, float] = {}
    for i, c in enumerate(problem.constraints):
        value = measured[i] if i in measured else c.violation(rollout.t, rollout.x, rollout.v)
        violations[c.family] = max(violations.get(c.family, 0.0), value)
    return violations


def _n_grid_rows(problem: FitProblem, x_lin: NDArray[np.float64]) -> int:
    """How many inequality rows strategy ``"full"`` hands the backend: every one on the constraint
    grid, linearised at the dense path ``x_lin`` [m]."""
    return sum(
        c.coefficients(problem.affine("grid").t, x_lin[:: problem.dense_factor]).bound.size
        for c in problem.constraints if not c.equality
    )


def solve_fit(
    problem: FitProblem,
    *,
    solver: str = "osqp",
    strategy: Strategy = "cutting_planes",
    tol: float = 1e-9,
    max_scp: int = 15,
    scp_tol: float = 1e-6,
    scp_rtol: float = 1e-6,
    coarse_samples: int | None = None,
    seed_with_backend: bool = True,
    options: dict[str, Any] | None = None,
    x_start: NDArray[np.float64] | None = None,
) -> FitResult:
    """Solve a :class:`FitProblem`.

    Args:
        solver: any installed qpsolvers backend (``qpsolvers.available_solvers``); default OSQP.
            It solves the whole problem in strategy ``"full"`` and the seed of the cutting planes
            when ``seed_with_backend`` is set.
        strategy: ``"cutting_planes"`` (whitened, lazy dense rows, exact dual active-set step) or
            ``"full"`` (plain condensed form on the constraint grid, one backend call).
        tol: accepted true violation [m or m/s]; status is ``"solved"`` when every family's
            dense-grid violation is within it, ``"inaccurate"`` otherwise.
        max_scp: rounds of re-linearisation for non-convex constraints; stop when the path moves
            less than ``scp_tol`` [m] or the objective changes by less than ``scp_rtol`` (relative).
        coarse_samples: about how many samples of the constraint grid seed the cutting planes
            (default ``COARSE_PER_BASIS * n_basis``).
        seed_with_backend: first let the backend (OSQP by default) solve the coarse rows the
            unconstrained optimum violates at moderate accuracy; its active rows become the exact
            step's first candidates. On by default (the backend takes part in every fit); off, the
            exact step starts from the unconstrained optimum alone (faster, the same optimum).
        options: backend options passed through qpsolvers.
        x_start: the path (T_dense, n) [m] on the dense grid (:attr:`FitProblem.t_dense`) the
            non-convex rows are first linearised at (default the unconstrained optimum's), e.g. the
            solution of the problem without some of its non-convex families.
    """
    check_solver(solver)
    if strategy not in ("cutting_planes", "full"):
        raise InputError("strategy", "'cutting_planes' or 'full'", repr(strategy))
    start = time.perf_counter()
    aff_d = problem.affine("dense")
    p, q = problem.quadratic()
    build_time = time.perf_counter() - start
    start = time.perf_counter()
    tw = _whitening(p) if strategy == "cutting_planes" else None
    w = unconstrained_weights(p, q) if tw is None else tw @ (-tw.T @ q)
    cnt = _Counter()
    nonconvex = any(c.linearised for c in problem.constraints)
    x_lin = aff_d.positions(w)
    if x_start is not None:
        x_lin = check_array(x_start, "x_start", shape=x_lin.shape)
    obj_prev = np.inf
    n_coarse = coarse_samples if coarse_samples else COARSE_PER_BASIS * problem.dmp.n_basis
    run = _ExactRun(solver, options, tol, max(1, round(np.asarray(problem.t).size / n_coarse)), seed_with_backend)
    exact = _Relinearised(problem, aff_d, tw, -tw.T @ q, run, cnt) if tw is not None else None
    scp = 0
    measured: dict[int, float] | None = None  # the violations the settled test measured at the final w
    try:
        for scp in range(1, max_scp + 1):
            if exact is not None:
                w = exact.step(x_lin, warm=scp > 1)
            else:
                w = _full(problem, p, q, x_lin, solver, options, cnt)
            x_new = aff_d.positions(w)
            moved = float(np.abs(x_new - x_lin).max())
            x_lin = x_new
            obj = float(0.5 * w @ p @ w + q @ w)
            # Conservative linearisations (tangent rows of a disc) keep every iterate feasible, so
            # stopping early only gives up objective. Others (a cone turning with the position) are
            # exact only at the linearisation path: there the objective test also needs the true
            # violation within tol.
            if not nonconvex:
                break
            if moved < scp_tol or abs(obj_prev - obj) <= scp_rtol * abs(obj):
                measured = _settled(problem, aff_d, w, x_new, tol)
                if measured is not None:
                    break
            obj_prev = obj
    except _Infeasible as inf:
        return FitResult(
            status="infeasible", solver=solver, strategy=strategy, build_time=build_time,
            solve_time=time.perf_counter() - start, iterations=cnt.iterations, n_qp=cnt.n_qp,
            scp_iterations=scp, families=inf.families, reason=inf.reason,
        )
    solve_time = time.perf_counter() - start
    rollout = _rollout(problem, aff_d, w, x_lin)  # x_lin: the positions of the final w
    violations = _dense_violations(problem, rollout, measured or {})
    n_rows = exact.active.size if exact is not None else _n_grid_rows(problem, x_lin)
    status: Literal["solved", "inaccurate"] = "solved" if max(violations.values(), default=0.0) <= tol else "inaccurate"
    return FitResult(
        status=status, solver=solver, strategy=strategy,
        weights=w.reshape(problem.dmp.n_basis, problem.dmp.n_dims), violations=violations,
        objective=float(0.5 * w @ p @ w + q @ w), rollout=rollout,
        build_time=build_time, solve_time=solve_time, iterations=cnt.iterations, n_qp=cnt.n_qp,
        n_rows=n_rows, scp_iterations=scp, exact_finish=cnt.finish, n_exact=cnt.n_exact,
    )
