"""Constrained fitting: promised constraints hold on the dense grid, backends agree, infeasibility."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.dmp import InfeasibleError, UnknownSolverError
from tooltransfer.dmp.qp import (
    FitProblem,
    FixedEndPoint,
    PositionPolygon,
    TrackPath,
    VelocityCone,
    build_fit_qp,
    solve_fit,
)
from tooltransfer.dmp.qp.problem import stack_rows
from tooltransfer.problems.fit_cases import l_push_case


def test_cutting_planes_hold_every_constraint_on_dense_grid() -> None:
    case = l_push_case(30, 200)
    r = solve_fit(case.problem)
    assert r.status == "solved"
    assert set(r.violations) == {"cone", "workspace", "endpoint", "end_velocity", "obstacle"}
    assert r.max_violation <= 1e-8
    assert np.linalg.norm(r.rollout.x[-1] - case.reference[-1]) < 1e-9  # terminal constraint
    assert r.n_qp == 1  # OSQP, the default backend, solved the coarse seed (then the exact step)


def test_backend_seed_reaches_the_same_exact_optimum() -> None:
    case = l_push_case(30, 200)
    plain = solve_fit(case.problem, max_scp=1, seed_with_backend=False)
    seeded = solve_fit(case.problem, max_scp=1)
    assert plain.n_qp == 0  # the exact step alone
    assert seeded.n_qp == 1  # OSQP solved the coarse seed
    assert seeded.status == plain.status == "solved"
    assert seeded.max_violation <= 1e-8
    assert abs(seeded.objective - plain.objective) <= 1e-9 * abs(plain.objective)


def test_unconstrained_fit_violates_so_constraints_are_active() -> None:
    case = l_push_case(30, 200)
    free = FitProblem(case.problem.dmp, case.t, case.reference[0], case.reference[-1], [TrackPath(case.reference)])
    r_free = solve_fit(free)
    r = solve_fit(case.problem)
    assert r.objective > r_free.objective + 1e-6


def test_optimum_matches_second_backend_on_the_same_dense_rows() -> None:
    quadprog = pytest.importorskip("quadprog")
    del quadprog
    case = l_push_case(20, 60, obstacle=False)
    prob = case.problem
    r = solve_fit(prob)
    # the same QP with every dense row, solved in one call by quadprog
    p, q = prob.quadratic()
    aff = prob.affine("dense")
    g, h, _, a, b, _ = stack_rows(prob.constraints, aff, r.rollout.x)
    from tooltransfer.dmp.qp.backends import solve_qp

    out = solve_qp(p, q, g, h, a, b, "quadprog")
    assert out.x is not None
    obj_ref = 0.5 * out.x @ p @ out.x + q @ out.x
    assert r.objective == pytest.approx(obj_ref, rel=1e-7, abs=1e-12)
    np.testing.assert_allclose(r.weights.ravel(), out.x, atol=1e-5 * np.abs(out.x).max())


def test_full_strategy_reports_its_true_dense_violation() -> None:
    case = l_push_case(30, 200)
    r = solve_fit(case.problem, strategy="full", max_scp=1)
    # the plain condensed form constrains only the grid; the dense check must reveal the rest
    assert r.violations["cone"] > 1e-7
    assert r.status == "inaccurate"


def test_infeasible_names_families() -> None:
    case = l_push_case(20, 100, obstacle=False)
    prob = case.problem
    bad = FitProblem(
        prob.dmp, prob.t, prob.x0, prob.g, prob.objectives,
        [VelocityCone(-np.pi / 4, 0.3), FixedEndPoint(prob.g)],  # goal lies up-left, cone points down-right
    )
    r = solve_fit(bad)
    assert r.status == "infeasible"
    assert "cone" in r.families
    with pytest.raises(InfeasibleError, match="cone"):
        r.raise_if_infeasible()


def test_build_is_separate_inspectable_and_saveable(tmp_path) -> None:
    case = l_push_case(10, 50, obstacle=False)
    qp = build_fit_qp(case.problem)
    assert qp.G.shape == (50 * 8, 20)  # 2 cone + 6 polygon rows per sample
    assert set(qp.row_family) == {"cone", "workspace"}
    qp.save(tmp_path / "qp.npz")
    assert np.load(tmp_path / "qp.npz")["P"].shape == (20, 20)
    assert qp.to_qpsolvers().P.shape == (20, 20)


def test_unknown_solver_lists_installed() -> None:
    case = l_push_case(10, 50, obstacle=False)
    with pytest.raises(UnknownSolverError, match="osqp"):
        solve_fit(case.problem, solver="no_such_solver")


def test_polygon_rejects_non_convex() -> None:
    from tooltransfer.dmp import InputError

    with pytest.raises(InputError, match="convex"):
        PositionPolygon.from_vertices([[0, 0], [1, 0], [0.2, 0.2], [0, 1]])


def test_outside_polygon_holds_on_the_dense_grid() -> None:
    import shapely

    from tooltransfer.dmp.qp import OutsidePolygon

    case = l_push_case(30, 200, obstacle=False)
    box = shapely.box(-0.004, 0.03, 0.01, 0.05)  # on the forward stretch of the L
    problem = FitProblem(
        case.problem.dmp, case.t, case.reference[0], case.reference[-1], [TrackPath(case.reference)],
        constraints=[OutsidePolygon(np.asarray(box.exterior.coords)[:-1], 0.003)],
    )
    r = solve_fit(problem)
    assert r.status == "solved"
    gap = shapely.distance(box, shapely.points(r.rollout.x)).min()
    assert gap >= 0.003 - 1e-9
    assert r.violations["obstacle"] <= 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_exact_step_matches_quadprog_cold_and_warm(seed: int) -> None:
    """The C dual active-set core (cold, and warm-started from a random guess of the active rows)
    reaches quadprog's optimum of ``min 0.5 |z - z_c|^2, E z = f, G z <= h``."""
    quadprog = pytest.importorskip("quadprog")
    from tooltransfer.dmp.qp.dual_active_set import DualActiveSet

    rng = np.random.default_rng(seed)
    n, m = 12, 60
    z_c = rng.normal(size=n)
    g = rng.normal(size=(m, n))
    g /= np.linalg.norm(g, axis=1)[:, None]
    inner = rng.normal(scale=0.3, size=n)
    h = g @ inner + rng.uniform(0.0, 0.2, m)  # feasible: ``inner`` meets every row
    e = rng.normal(size=(1, n))
    f = e @ inner
    ref = quadprog.solve_qp(np.eye(n), z_c, -np.vstack([e, g]).T, -np.concatenate([f, h]), meq=1)[0]
    n_act = int(np.sum(g @ ref - h > -1e-9))
    assert n_act >= 3  # the rows matter
    for warm in (None, rng.choice(m, size=n_act + 3, replace=False)):
        st = DualActiveSet(z_c, g, h)
        st.add_equalities(e, f)
        if warm is not None:
            st.warm_start(warm)
        z = st.solve(lambda _z: (np.zeros((0, n)), np.zeros(0)))
        np.testing.assert_allclose(z, ref, atol=1e-10)
        assert (g @ z - h).max() <= 1e-12


def test_compiled_scan_matches_numpy_residuals_and_peaks() -> None:
    """The oracle's compiled scan gives the NumPy residuals and local maxima on every kind of sample set."""
    from tooltransfer.dmp.qp.pool import RowPool, Samples
    from tooltransfer.dmp.qp.problem import unconstrained_weights

    prob = l_push_case(20, 80).problem
    aff = prob.affine("dense")
    w = unconstrained_weights(*prob.quadratic())
    pool = RowPool.build(prob.constraints, aff, aff.positions(w))
    for cols in (slice(0, None, 10), slice(None), np.arange(3, aff.t.size, 7)):
        smp = Samples.of(aff, cols)
        res = pool.residuals(w, smp)
        ids, res_c = pool.scan(w, smp, 1e-9, keep=True)
        assert res_c is not None
        np.testing.assert_allclose(res_c, res, rtol=0, atol=1e-15)
        peaks = pool.peaks(res, smp, 1e-9)
        assert peaks.size > 0  # the unconstrained fit violates rows
        np.testing.assert_array_equal(np.sort(ids), np.sort(peaks))


def test_pool_rows_equal_the_condensed_rows() -> None:
    """Rows built by the compiled core for row ids equal the condensed form's rows (``stack_rows``)."""
    from tooltransfer.dmp.qp.pool import RowPool
    from tooltransfer.dmp.qp.problem import unconstrained_weights

    prob = l_push_case(20, 80).problem
    aff = prob.affine("dense")
    x = aff.positions(unconstrained_weights(*prob.quadratic()))
    pool = RowPool.build(prob.constraints, aff, x)
    g, h, fam, *_ = stack_rows(prob.constraints, aff, x)
    ids = []
    for ci, c in enumerate(prob.constraints):  # stack_rows is sample-major; ids are row-major
        if not c.equality:
            kk, m = pool.coeffs[ci].k.size, pool.coeffs[ci].bound.shape[1]
            ids.append(pool.offset[ci] + (np.arange(m)[None, :] * kk + np.arange(kk)[:, None]).ravel())
    g_pool, h_pool = pool.rows(np.concatenate(ids))
    np.testing.assert_allclose(g_pool, g, rtol=0, atol=1e-14 * np.abs(g).max())
    np.testing.assert_allclose(h_pool, h, rtol=0, atol=1e-14 * np.abs(h).max())
    assert pool.families(np.arange(pool.size)) == set(fam)


def test_misleading_warm_start_is_proved_again_cold(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every coarse row guessed active at once (far more than the 60 variables, nearly dependent):
    the warm-started exact step ends in a spurious infeasibility proof, the step is re-run cold, and
    the optimum is the cold one."""
    import tooltransfer.dmp.qp.solve as S
    from tooltransfer.dmp.qp.pool import RowPool, Samples

    case = l_push_case(30, 200)
    pr = case.problem
    aff = pr.affine("dense")
    p, q = pr.quadratic()
    tw = S._whitening(p)
    z_c = -tw.T @ q
    pool = RowPool.build(pr.constraints, aff, aff.positions(tw @ z_c))
    grid = Samples.of(aff, slice(0, None, pr.dense_factor))
    levels = S._Levels(grid, Samples.of(aff, slice(None)), pr.dense_factor, pool.outside_grid(grid))
    cold = solve_fit(pr, max_scp=1, seed_with_backend=False)
    runs: list[bool] = []
    inner = S._cutting_planes

    def spy(*args: object, **kw: object) -> object:
        runs.append(args[3] is None)  # seed None: a cold run
        return inner(*args, **kw)

    monkeypatch.setattr(S, "_cutting_planes", spy)
    qp, run = S._WhitenedQP(pool, levels, tw, z_c), S._ExactRun("osqp", None, 1e-9, 3, False)
    z, _, _ = spy(qp, run, S._Counter(), pool.coarse_ids(20))
    assert runs == [False, True]  # warm, then cold
    w = tw @ z
    assert abs(0.5 * w @ p @ w + q @ w - cold.objective) <= 1e-9 * abs(cold.objective)
