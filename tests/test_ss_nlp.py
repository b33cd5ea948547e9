"""The switch NLP's rows (built vectorized over the knots) against a knot-by-knot numpy evaluation."""

from __future__ import annotations

import numpy as np

from tooltransfer.planner.ss.bodies import UNIT, all_bodies
from tooltransfer.planner.ss.cases import fig11_task
from tooltransfer.planner.ss.nlp import build_nlp
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
