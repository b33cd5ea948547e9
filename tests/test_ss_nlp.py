"""The switch NLP: its rows (mapped over the knots) against a knot-by-knot numpy evaluation, and the
derivatives it hands IPOPT against CasADi's own, in value and in the solves they give."""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np
import pytest
import shapely

from tooltransfer.planner.planning.ss import OptOptions, SwitchTask, learn_switch_skill, optimize
from tooltransfer.planner.planning.ss import nlp as nlp_module
from tooltransfer.planner.planning.ss.bodies import UNIT, all_bodies
from tooltransfer.planner.planning.ss.cases import fig11_task
from tooltransfer.planner.planning.ss.nlp import build_nlp, clear_cache
from tooltransfer.planner.planning.ss.synthetic import synthetic_switches
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.heading import heading
from tooltransfer.tools.omni.reach import reach_sector, wedge_rows


def test_rows_knot_by_knot_in_order() -> None:
    """Disc object and a disc obstacle, vector separators, all reach rows: every row of the built NLP
    equals its formula evaluated one knot at a time, in the documented order (body, knot, piece,
    vertex rows then the norm row; reach rows per knot; step rows)."""
    rng = np.random.default_rng(3)
    task = fig11_task("fig11b")
    obstacles = (Disc(np.array([0.05, 0.17]), 0.01),)
    bodies = all_bodies(task.shape, obstacles)
    N = 9
    nlp = build_nlp(task.tool, N, task.omni, bodies, reach=True, separators="vector")
    X = (np.array([0.0, 0.16]) + rng.uniform(-0.03, 0.03, (N, 2))) / UNIT  # (N, 2) [mm]
    S = rng.normal(size=(nlp.n_sep, N - 2))
    m_obj, m_obs = rng.uniform(0, 2, N), rng.uniform(0, 2, N)
    s_max = 25.0
    p = np.concatenate([X.ravel() + 1.0, m_obj, m_obs, *[b.data for b in bodies], [s_max]])
    z = np.concatenate([X.ravel(), S.ravel(order="F")])
    g = np.asarray(nlp.rows(z, p)).ravel()
    yaw = heading(task.omni, X * UNIT)
    expected = []
    for bi, b in enumerate(bodies):
        m = m_obj if b.family == "object" else m_obs
        for k in range(1, N - 1):
            c, s = np.cos(yaw[k]), np.sin(yaw[k])
            R = np.array([[c, -s], [s, c]])
            for j, verts in enumerate(nlp.pieces):
                off = next(o for (jj, bb, o, _) in nlp.sep_layout if jj == j and bb == bi)
                n = S[off:off + 2, k - 1]
                for v in verts:
                    w = X[k] + R @ v
                    expected.append(n @ (w - b.data[:2]) - (b.data[2] + m[k]))
                expected.append(1 - n @ n)
    sec_rows = []
    sec, wr = reach_sector(task.omni), wedge_rows(task.omni)
    r_in, r_out = (sec.r_in + 1e-4) / UNIT, (sec.r_out - 1e-4) / UNIT
    for k in range(1, N - 1):
        r2 = float(np.sum((X[k] - sec.centre / UNIT) ** 2))
        sec_rows += [(r2 - r_in**2) / r_in, (r_out**2 - r2) / r_out]
        sec_rows += [wr.h[gi] / UNIT - 1e-4 / UNIT - wr.G[gi] @ X[k] for gi in range(2)]
    steps = [(s_max**2 - float(np.sum((X[k + 1] - X[k]) ** 2))) / s_max for k in range(N - 1)]
    expected = np.array(expected + sec_rows + steps)
    assert g.shape == expected.shape
    np.testing.assert_allclose(g, expected, rtol=1e-12, atol=1e-9)
    assert [f for f, _, _ in nlp.families] == ["object", "obstacle 0", "reach", "step"]


def test_distance_rows_are_shapely_signed_distances() -> None:
    """``separators="distance"``: each disc body's row per knot and piece is the signed distance from
    the disc's centre to the placed piece (shapely: distance outside, minus the depth to the
    boundary inside) less radius and margin, with no separating variables."""
    import shapely
    from shapely.affinity import rotate, translate

    rng = np.random.default_rng(5)
    task = fig11_task("fig11a")  # the T-shape: two convex pieces
    obstacles = (Disc(np.array([0.03, 0.18]), 0.012),)
    bodies = all_bodies(task.shape, obstacles)
    N = 12
    nlp = build_nlp(task.tool, N, task.omni, bodies, reach=False, separators="distance")
    assert nlp.n_sep == 0 and len(nlp.pieces) == 2
    X = (task.centre + rng.uniform(-0.04, 0.04, (N, 2))) / UNIT  # some knots put a piece over the centre
    m_obj, m_obs = rng.uniform(0, 2, N), rng.uniform(0, 2, N)
    p = np.concatenate([X.ravel(), m_obj, m_obs, *[b.data for b in bodies], [25.0]])
    g = np.asarray(nlp.rows(X.ravel(), p)).ravel()
    yaw = heading(task.omni, X * UNIT)
    expected, inside = [], 0
    for b in bodies:
        m = m_obj if b.family == "object" else m_obs
        centre = shapely.Point(*b.data[:2])
        for k in range(1, N - 1):
            for verts in nlp.pieces:
                piece = translate(rotate(shapely.Polygon(verts), yaw[k], origin=(0, 0), use_radians=True), *X[k])
                d = piece.exterior.distance(centre)
                if piece.contains(centre):
                    d, inside = -d, inside + 1
                expected.append(d - (b.data[2] + m[k]))
    n_body = len(expected)
    np.testing.assert_allclose(g[:n_body], expected, atol=1e-6)
    assert inside > 0  # the inside branch was exercised


def _casadis_own(nlp: nlp_module.SwitchNLP) -> tuple[ca.Function, ca.Function, ca.Function]:
    """CasADi's automatic gradient, Jacobian and Lagrangian Hessian (upper triangle) of the NLP's
    objective and rows, as functions of (z, p) and (z, p, lam_f, lam_g)."""
    z, p = ca.MX.sym("z", nlp.n_vars), ca.MX.sym("p", nlp.n_params)
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", nlp.lbg.size)
    f = nlp.solver.get_function("nlp_f")(z, p)
    g = nlp.rows(z, p)
    hess = ca.triu(ca.hessian(lam_f * f + ca.dot(lam_g, g), z)[0])
    return (ca.Function("own_grad", [z, p], [ca.gradient(f, z)]), ca.Function("own_jac", [z, p], [ca.jacobian(g, z)]),
            ca.Function("own_hess", [z, p, lam_f, lam_g], [hess]))


_POLYGON = shapely.box(0.03, 0.15, 0.045, 0.17)
_DISC = Disc(np.array([0.05, 0.17]), 0.01)
_SQUARE_OBJECT = shapely.box(-0.015, 0.145, 0.015, 0.175)


@pytest.mark.parametrize(("tool", "model", "separators", "obj", "obstacles", "reach", "n_knots"), [
    ("trapezoid", "pieces", "distance", None, (_DISC,), True, 9),
    ("trapezoid", "pieces", "distance", None, (_POLYGON,), (False, True, False), 9),
    ("trapezoid", "pieces", "vector", None, (_DISC, _POLYGON), True, 9),
    ("trapezoid", "pieces", "angle", None, (_DISC,), False, 9),
    ("trapezoid", "capsule", "distance", None, (_DISC,), True, 9),
    ("l_shape", "pieces", "distance", None, (_DISC,), (False, False, True), 5),  # two pieces; wedge rows only
    ("l_shape", "pieces", "distance", _SQUARE_OBJECT, (_DISC, _POLYGON), (True, False, False), 6),
])
def test_derivatives_equal_casadis_own(tool: str, model: str, separators: str, obj: object, obstacles: tuple,
                                       reach: object, n_knots: int) -> None:
    """The gradient, Jacobian and Lagrangian Hessian IPOPT gets (derived for one knot and mapped)
    equal CasADi's automatic derivatives of the whole problem at random points, with the same
    sparsity patterns (the Hessian's upper triangle); the gradient is stored dense (IPOPT reads it as
    a dense vector: a sparse one left the separators' entries unset and sent IPOPT astray)."""
    rng = np.random.default_rng(7)
    task = fig11_task("fig11b")
    bodies = all_bodies(task.shape if obj is None else obj, obstacles)
    N = n_knots
    nlp = build_nlp(load_tool(tool), N, task.omni, bodies, model=model, separators=separators, reach=reach)
    grad, jac, hess = (nlp.solver.get_function(n) for n in ("nlp_grad_f", "nlp_jac_g", "nlp_hess_l"))
    assert grad.sparsity_out(1).is_dense()
    own_grad, own_jac, own_hess = _casadis_own(nlp)
    assert jac.sparsity_out(1) == own_jac.sparsity_out(0)
    assert hess.sparsity_out(0) == own_hess.sparsity_out(0) and hess.sparsity_out(0).is_triu()
    for _ in range(4):
        X = (np.array([0.0, 0.16]) + rng.uniform(-0.03, 0.03, (N, 2))) / UNIT
        z = np.concatenate([X.ravel(), rng.normal(size=nlp.n_vars - X.size)])
        p = np.concatenate([X.ravel() + 1.0, rng.uniform(0, 2, 2 * N), *[b.data for b in bodies], [25.0]])
        lam = rng.normal(size=nlp.lbg.size)
        np.testing.assert_allclose(grad(z, p)[1].full(), own_grad(z, p).full(), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(jac(z, p)[1].full(), own_jac(z, p).full(), rtol=1e-12, atol=1e-12)
        got, want = hess(z, p, 0.7, lam).full(), own_hess(z, p, 0.7, lam).full()
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10 * np.abs(want).max())


def test_ipopt_solves_as_with_casadis_own_derivatives(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every solve of a switch past a disc and a polygon obstacle (separating variables) ends as IPOPT
    given CasADi's own derivatives of the problem does: the same status and path, and the iteration
    counts within rounding's reach (equal here; rounding can change the count of a long solve)."""
    compared: list[int] = []

    class Twin:
        """The NLP's solver, and beside it IPOPT with CasADi's derivatives of the same f and g."""

        def __init__(self, problem: dict, derivatives: Callable[[], dict], max_iter: int) -> None:
            self.ours = ipopt(problem, derivatives, max_iter)
            self.own = ipopt(problem, dict, max_iter)  # no derivatives given: CasADi derives the MX graph

        def __call__(self, **args: object) -> dict:
            got, want = self.ours(**args), self.own(**args)
            mine, theirs = self.ours.stats(), self.own.stats()
            assert mine["return_status"] == theirs["return_status"]
            assert abs(mine["iter_count"] - theirs["iter_count"]) <= max(1, theirs["iter_count"] // 10)
            np.testing.assert_allclose(got["x"].full(), want["x"].full(), rtol=1e-6, atol=1e-6)  # [mm]
            compared.append(mine["iter_count"])
            return got

        def stats(self) -> dict:
            return self.ours.stats()

    ipopt = nlp_module.SOLVERS["ipopt"]
    monkeypatch.setitem(nlp_module.SOLVERS, "ipopt", Twin)
    clear_cache()
    skill = learn_switch_skill(synthetic_switches(5, seed=1), virtual="arch", tool="finger")
    c = np.array([0.0, 0.16])
    task = SwitchTask(load_tool("finger"), "upper", "left", c,
                      obstacles=(Disc(c + np.array([0.055, 0.02]), 0.01), shapely.box(-0.075, 0.17, -0.06, 0.185)))
    try:
        path = optimize(skill, task, OptOptions(body_band=None))  # every obstacle in the NLP
        separated = [nlp.n_sep > 0 for nlp in nlp_module._CACHE.values()]  # the polygon's separating variables
    finally:
        clear_cache()
    assert path.ok, path.reason
    assert compared and sum(compared) > 5 and any(separated)
