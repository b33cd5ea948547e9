"""The NumPy dual active-set core (the fallback without a compiler) gives the compiled core's optima
and infeasibility proofs; it is chosen, with one warning, when the compiled core is absent, and by
``TOOLTRANSFER_NO_NATIVE=1``; the whole planner runs on it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import shapely

from tooltransfer.dmp.qp import FitProblem, FixedEndPoint, OutsidePolygon, TrackPath, VelocityCone, native, solve_fit
from tooltransfer.dmp.qp.dual_active_set import DualActiveSet, DualInfeasible
from tooltransfer.problems.fit_cases import l_push_case

ROOT = Path(__file__).resolve().parents[1]
compiled = pytest.mark.skipif(native.compiled_path() is None, reason="the compiled core is not built")


def _cone_against_goal() -> FitProblem:
    p = l_push_case(20, 100, obstacle=False).problem
    return FitProblem(p.dmp, p.t, p.x0, p.g, p.objectives, [VelocityCone(-np.pi / 4, 0.3), FixedEndPoint(p.g)])


def _endpoint_outside_workspace() -> FitProblem:
    """The end point is fixed outside the workspace hexagon: equality and polygon rows conflict."""
    p = l_push_case(20, 100, obstacle=False).problem
    return FitProblem(p.dmp, p.t, p.x0, p.g, p.objectives, [p.constraints[1], FixedEndPoint([0.05, 0.1])])


def _outside_box() -> FitProblem:
    case = l_push_case(30, 200, obstacle=False)
    box = shapely.box(-0.004, 0.03, 0.01, 0.05)
    return FitProblem(case.problem.dmp, case.t, case.reference[0], case.reference[-1], [TrackPath(case.reference)],
                      constraints=[OutsidePolygon(np.asarray(box.exterior.coords)[:-1], 0.003)])


CASES = {
    "l_push_30x200": lambda: l_push_case(30, 200).problem,
    "l_push_20x100_no_disc": lambda: l_push_case(20, 100, obstacle=False).problem,
    "l_push_narrow_cone": lambda: l_push_case(30, 200, theta_b=0.3).problem,
    "l_push_60x1000": lambda: l_push_case(60, 1000).problem,
    "outside_polygon": _outside_box,
    "infeasible_cone": _cone_against_goal,
    "infeasible_endpoint": _endpoint_outside_workspace,
}


@compiled
@pytest.mark.parametrize("seed", [True, False], ids=["osqp_seed", "exact_alone"])
@pytest.mark.parametrize("name", list(CASES))
def test_numpy_core_reaches_the_compiled_optimum(name: str, seed: bool) -> None:
    problem = CASES[name]()
    with native.using("compiled"):
        ref = solve_fit(problem, seed_with_backend=seed)
    with native.using("numpy"):
        got = solve_fit(problem, seed_with_backend=seed)
    assert got.status == ref.status
    if ref.status == "infeasible":
        assert got.families == ref.families and got.families
        return
    assert ref.status == "solved"
    assert abs(got.objective - ref.objective) <= 1e-9 * abs(ref.objective)
    assert got.max_violation <= 1e-9
    np.testing.assert_allclose(got.rollout.x, ref.rollout.x, rtol=0, atol=1e-9)  # [m]
    assert abs(got.n_exact - ref.n_exact) <= 0.02 * ref.n_exact + 2  # the same steps (equal here; ties may differ)


def _random_qp(seed: int, feasible: bool) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    n, m = 12, 60
    z_c = rng.normal(size=n)
    g = rng.normal(size=(m, n))
    g /= np.linalg.norm(g, axis=1)[:, None]
    inner = rng.normal(scale=0.3, size=n)
    h = g @ inner + rng.uniform(0.0, 0.2, m)
    if not feasible:  # a row and its opposite with a gap: g0 z <= h0 and -g0 z <= -h0 - 0.1
        g = np.vstack([g, -g[:1]])
        h = np.append(h, -h[0] - 0.1)
    e = rng.normal(size=(1, n))
    f = e @ inner
    return z_c, g, h, e, f


def _run(which: str, z_c, g, h, e, f, warm) -> tuple[np.ndarray | None, object, int]:
    with native.using(which):
        st = DualActiveSet(z_c, g, h)
    st.add_equalities(e, f)
    if warm is not None:
        st.warm_start(warm)
    try:
        return st.solve(lambda _z: (np.zeros((0, z_c.size)), np.zeros(0))).copy(), None, st.iterations
    except DualInfeasible as inf:
        return None, (sorted(inf.rows), inf.equalities), st.iterations


@compiled
@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("feasible", [True, False])
def test_exact_step_matches_compiled_cold_and_warm(seed: int, feasible: bool) -> None:
    """Random QPs ``min 0.5 |z - z_c|^2, E z = f, G z <= h``: the same optimum, or the same
    infeasibility proof (rows involved, equalities or not), cold and warm-started."""
    z_c, g, h, e, f = _random_qp(seed, feasible)
    rng = np.random.default_rng(100 + seed)
    for warm in (None, rng.choice(g.shape[0], size=15, replace=False)):
        z_ref, proof_ref, it_ref = _run("compiled", z_c, g, h, e, f, warm)
        z, proof, it = _run("numpy", z_c, g, h, e, f, warm)
        assert proof == proof_ref
        assert it == it_ref
        if feasible:
            assert z is not None and z_ref is not None
            np.testing.assert_allclose(z, z_ref, rtol=0, atol=1e-12)
        else:
            assert z is None and proof is not None and g.shape[0] - 1 in proof[0]


def test_numpy_core_alone_meets_every_row() -> None:
    """Without comparing to the compiled core (which may be absent): the NumPy steps reach a point
    that meets every row, with the multipliers' optimality conditions."""
    z_c, g, h, e, f = _random_qp(3, True)
    z, proof, _ = _run("numpy", z_c, g, h, e, f, None)
    assert proof is None and z is not None
    assert (g @ z - h).max() <= 1e-12
    assert np.abs(e @ z - f).max() <= 1e-12
    act = g @ z - h > -1e-9
    lhs = np.vstack([e, g[act]]).T  # z_c - z = E^T y + G_act^T u, u >= 0
    sol, *_ = np.linalg.lstsq(lhs, z_c - z, rcond=None)
    np.testing.assert_allclose(lhs @ sol, z_c - z, atol=1e-10)
    assert sol[1:].min() >= -1e-10


@compiled
def test_scan_and_rows_match_the_compiled_core() -> None:
    from tooltransfer.dmp.qp.pool import RowPool, Samples
    from tooltransfer.dmp.qp.problem import unconstrained_weights

    prob = l_push_case(20, 80).problem
    aff = prob.affine("dense")
    w = unconstrained_weights(*prob.quadratic())
    pool = RowPool.build(prob.constraints, aff, aff.positions(w))
    for cols in (slice(0, None, 10), slice(None), np.arange(3, aff.t.size, 7)):
        smp = Samples.of(aff, cols)
        with native.using("compiled"):
            ids_c, res_c = pool.scan(w, smp, 1e-9, keep=True)
            g_c, h_c = pool.rows(ids_c)
        with native.using("numpy"):
            ids_n, res_n = pool.scan(w, smp, 1e-9, keep=True)
            g_n, h_n = pool.rows(ids_n)
            assert pool.scan(w, smp, 1e-9)[0].tolist() == ids_n.tolist()  # without keeping residuals
        assert ids_n.size > 0
        np.testing.assert_array_equal(ids_n, ids_c)
        np.testing.assert_allclose(res_n, res_c, rtol=0, atol=1e-15)
        np.testing.assert_allclose(g_n, g_c, rtol=0, atol=1e-14 * np.abs(g_c).max())
        np.testing.assert_allclose(h_n, h_c, rtol=0, atol=1e-14 * np.abs(h_c).max())


def test_scan_reports_every_peak_beyond_a_small_buffer() -> None:
    """More peaks than the output buffer holds: the count says so and the pool asks again."""
    from tooltransfer.dmp.qp.pool import RowPool, Samples
    from tooltransfer.dmp.qp.problem import unconstrained_weights

    prob = l_push_case(20, 80).problem
    aff = prob.affine("dense")
    w = unconstrained_weights(*prob.quadratic())
    pool = RowPool.build(prob.constraints, aff, aff.positions(w))
    smp = Samples.of(aff, slice(None))
    with native.using("numpy"):
        full = pool.scan(w, smp, -1.0)[0]  # every local maximum of every applicable series
        pool._out = (np.empty(1, dtype=np.int32), np.empty(1, dtype=np.int64))
        again = pool.scan(w, smp, -1.0)[0]
    assert full.size > 1
    np.testing.assert_array_equal(again, full)


def test_missing_compiled_core_warns_once_and_falls_back(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(native.ENV_VAR, raising=False)
    monkeypatch.setattr(native, "compiled_path", lambda: None)
    native.default_core.cache_clear()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            first, second = native.core(), native.core()
            r = solve_fit(l_push_case(10, 50, obstacle=False).problem)
        msgs = [w for w in caught if issubclass(w.category, native.NativeCoreWarning)]
        assert len(msgs) == 1
        text = str(msgs[0].message)
        assert "\n" not in text and "NumPy" in text
        assert first is second and first.name == "numpy"
        assert r.status == "solved"
    finally:
        native.default_core.cache_clear()


def test_unknown_core_name_is_refused() -> None:
    with pytest.raises(ValueError, match="compiled"), native.using("fortran"):
        pass


def _python(code: str, **env: str) -> subprocess.CompletedProcess[str]:
    full = {**os.environ, "OPENBLAS_NUM_THREADS": "1", **env}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=full,
                          timeout=600, check=False)


def test_environment_variable_forces_the_numpy_core_silently() -> None:
    code = ("import warnings; warnings.simplefilter('error')\n"
            "from tooltransfer.dmp.qp import native, solve_fit\n"
            "from tooltransfer.problems.fit_cases import l_push_case\n"
            "r = solve_fit(l_push_case(10, 50, obstacle=False).problem)\nprint(native.core().name, r.status)")
    out = _python(code, TOOLTRANSFER_NO_NATIVE="1")
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["numpy", "solved"]
    if native.compiled_path() is not None:
        out = _python(code, TOOLTRANSFER_NO_NATIVE="0")
        assert out.returncode == 0, out.stderr
        assert out.stdout.split() == ["compiled", "solved"]


def test_planner_solves_the_transfer_task_without_the_compiled_core() -> None:
    """``tooltransfer.planner.planning.solve.solve`` on the paper's transfer task, in a fresh process with the core
    disabled."""
    code = (
        "import json\nfrom tooltransfer.planner.planning.solve import solve\n"
        "from tooltransfer.problems.task import load_task\n"
        "from tooltransfer.dmp.qp import native\n"
        "path = 'problems/paper/transfer_tool2.yaml'\nplan = solve(load_task(path), path)\n"
        "print(json.dumps({'core': native.core().name, 'status': plan.status, 'reason': plan.reason,"
        " 'goal_error': plan.metrics.get('goal_error')}))"
    )
    out = _python(code, TOOLTRANSFER_NO_NATIVE="1")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout.strip().splitlines()[-1])
    assert doc["core"] == "numpy"
    assert doc["status"] == "solved", doc["reason"]
    assert doc["goal_error"] <= 1e-3
