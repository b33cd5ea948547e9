"""OE condensing, ``qp`` variant: face frames on the Omni, reach rows, heading cone, push search."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import shapely
import yaml

from tooltransfer.planner.planning.oe import QPOptions, condense_qp
from tooltransfer.planner.planning.oe.constraints import HeadingCone, reach_constraints
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.problems.fit_cases import minimum_jerk
from tooltransfer.tools import Disc, load_tool, tool_from_dict
from tooltransfer.tools.library import library_names
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import DiscObject
from tooltransfer.tools.omni.ik import inverse_kinematics
from tooltransfer.tools.omni.platform import OmniPlatform

R = 0.0175


def setting_for(tool: Tool, radius: float = R, **kw: object) -> Setting:
    """The setting of ``tool`` on its Omni pushing a puck of ``radius`` [m] (``kw``: obstacles, margin)."""
    return Setting(tool, OmniPlatform(a_t=tool.a_t), DiscObject(radius), **kw)  # type: ignore[arg-type]


def _along_normal(tool_name: str, face: str, start: np.ndarray, length: float, n: int) -> np.ndarray:
    """``n`` points [m] from ``start`` along ``face``'s normal at the heading the Omni imposes there
    (a path the face pushes without sliding or leaving the face: what the mechanics allow)."""
    tool = load_tool(tool_name)
    fr = FaceFrame.build(setting_for(tool), face)
    out = [np.asarray(start, float)]
    for _ in range(n - 1):
        d = float(fr.normal_direction(out[-1][None])[0])
        out.append(out[-1] + length / (n - 1) * np.array([np.cos(d), np.sin(d)]))
    return np.array(out)


START = np.array([0.05, 0.12])
CORNER = _along_normal("slope", "left", START, 0.07, 400)[-1]
TARGET = _along_normal("slope", "inclined", CORNER, 0.06, 400)[-1]


def l_scene(n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """A two-leg universal path (6 s): leftward, then forward-left, each leg along the slope's face
    normals at the headings there (the left face's, then the inclined face's), so that the tool can
    push it: the inclined face's normal points at 5 pi / 6 plus the heading, not at the 0.75 pi its
    file names."""
    t = np.linspace(0.0, 6.0, n)
    x = np.vstack([minimum_jerk(START, CORNER, n // 2), minimum_jerk(CORNER, TARGET, n - n // 2)])
    return t, x


@pytest.mark.parametrize("name", library_names())
def test_face_frame_pose_matches_the_omni_heading(name: str) -> None:
    tool = load_tool(name)
    plat = OmniPlatform(a_t=tool.a_t)
    rng = np.random.default_rng(1)
    for face in tool.face_names:
        fr = FaceFrame.build(setting_for(tool), face)
        poly, disc = reach_constraints(fr)
        pts = rng.uniform([-0.25, -0.05], [0.25, 0.25], (4000, 2))
        inside = np.all(pts @ poly.A.T <= poly.b, axis=1) & (np.linalg.norm(pts - disc.center, axis=1) >= disc.radius)
        assert inside.sum() > 200
        for pose in fr.tool_pose(pts[inside][:60]):
            ik = inverse_kinematics(plat, pose[:2])
            assert ik.reachable  # the rows are an inner approximation of the reach
            assert abs(ik.heading - pose[2]) < 1e-9  # the heading the Omni imposes there


def test_reach_rows_cover_nearly_all_of_the_exact_region() -> None:
    tool = load_tool("slope")
    plat = OmniPlatform(a_t=tool.a_t)
    fr = FaceFrame.build(setting_for(tool), "inclined")
    poly, disc = reach_constraints(fr, tol=2e-4)
    pts = np.random.default_rng(2).uniform([-0.25, -0.05], [0.25, 0.25], (20000, 2))
    inside = np.all(pts @ poly.A.T <= poly.b, axis=1) & (np.linalg.norm(pts - disc.center, axis=1) >= disc.radius)
    exact = np.array([
        (ik := inverse_kinematics(plat, p[:2])).reachable and abs(ik.heading - p[2]) < 1e-9 for p in fr.tool_pose(pts)
    ])
    assert not np.any(inside & ~exact)
    assert inside.sum() >= 0.99 * exact.sum()


def test_heading_cone_rows_follow_the_heading() -> None:
    tool = load_tool("slope")
    fr = FaceFrame.build(setting_for(tool), "left")
    x = np.array([[0.05, 0.15], [-0.06, 0.15]])
    phi = fr.push_direction(x)
    assert abs(phi[0] - phi[1]) > 0.3  # the cone turns with the waist
    c = HeadingCone(fr)
    co = c.coefficients(np.arange(2.0), x)
    along = np.stack([np.cos(phi), np.sin(phi)], 1) * 0.01
    assert np.all(co.residuals(x, along) <= 1e-15)
    off = np.stack([np.cos(phi + fr.theta_b + 0.1), np.sin(phi + fr.theta_b + 0.1)], 1) * 0.01
    assert np.all(co.residuals(x, off).max(axis=1) > 0)
    assert c.angle_violation(x, off) == pytest.approx(0.1, abs=1e-12)


def test_qp_variant_condenses_an_l_path_for_the_slope_tool() -> None:
    tool = load_tool("slope")
    t, x = l_scene()
    obstacle = Disc(np.array([0.02, 0.1]), 0.006)
    plan = condense_qp(t, x, setting_for(tool, obstacles=(obstacle,)))
    assert plan.status == "solved", plan.reason
    m = plan.metrics
    assert plan.faces[0] == "left" and "inclined" in plan.faces
    # the mechanics hold on every push: inside the friction cone, the contact on its face
    assert m["friction_cone_margin_min"] > 0.0
    assert m["contact_edge_margin_min"] >= -1e-9
    for p in plan.pushes:
        lo, hi = 0.0, tool.face(p.face).length
        assert np.all((p.contact_s >= lo - 1e-9) & (p.contact_s <= hi + 1e-9))
    assert m["goal_error"] < 1e-3
    assert m["reach_violation_max"] <= 1e-6
    assert m["obstacle_clearance_min"] >= 0.005 - 1e-6  # the safety margin
    assert all(v <= 1e-6 for k, v in m.items() if k.startswith("violation_"))
    assert m["deviation_max"] < 0.01
    # consecutive pushes share their switch instant; every push's tool pose is reachable
    for a, b in itertools.pairwise(plan.pushes):
        assert a.t_end == b.t_start
        assert b.recontact == (a.face == b.face)
    plat = OmniPlatform(a_t=tool.a_t)
    for p in plan.pushes:
        assert all(inverse_kinematics(plat, pose[:2]).reachable for pose in p.tool_pose[::25])
    assert plan.n_qp >= len(plan.candidates)


def test_target_out_of_reach_is_infeasible_with_reason() -> None:
    tool = load_tool("slope")
    t, x = l_scene()
    x = x + np.linspace(0, 1, t.size)[:, None] * np.array([0.0, 0.3])  # ends 0.48 m from the base
    plan = condense_qp(t, x, setting_for(tool))
    assert plan.status == "infeasible"
    assert "target outside the Omni's reach for every face" in plan.reason
    assert plan.n_qp == 0


def test_a_tool_that_only_pushes_away_from_the_target_is_infeasible() -> None:
    with open("tools/library/finger.yaml") as fh:
        spec = yaml.safe_load(fh)
    spec["faces"] = [f for f in spec["faces"] if f["name"] == "upper"]  # forward pushes only
    tool = tool_from_dict(spec)
    t = np.linspace(0.0, 4.0, 150)
    x = minimum_jerk(np.array([0.0, 0.19]), np.array([0.0, 0.14]), t.size)  # towards the base
    plan = condense_qp(t, x, setting_for(tool), options=QPOptions(candidates=2))
    assert plan.status == "infeasible"
    assert "cone" in plan.reason


def test_qp_variant_keeps_the_margin_from_a_polygon_obstacle() -> None:
    tool = load_tool("slope")
    t, x = l_scene()
    box = shapely.box(0.0, 0.09, 0.02, 0.105)  # just below the leftward stretch: pass 6.5 mm higher
    plan = condense_qp(t, x, setting_for(tool, obstacles=(box,), margin=0.004))
    assert plan.status == "solved", plan.reason
    gap = shapely.distance(box, shapely.points(plan.object_xy)).min() - R
    assert gap >= 0.004 - 1e-6
    assert plan.metrics["obstacle_clearance_min"] == pytest.approx(gap, abs=1e-12)


def test_mapping_variant_runs_from_start_to_target_and_reports_what_it_violates() -> None:
    from tooltransfer.planner.planning.oe.mapping_variant import MappingOptions, condense_mapping

    tool = load_tool("slope")
    t, x = l_scene()
    obstacle = Disc(np.array([0.02, 0.1]), 0.006)
    plan = condense_mapping(t, x, setting_for(tool, obstacles=(obstacle,)),
                            options=MappingOptions(tube=0.015))
    assert plan.status == "solved"
    assert np.allclose(plan.object_xy[0], START) and np.allclose(plan.object_xy[-1], TARGET)
    assert set(plan.faces) <= {"left", "inclined"} and len(plan.faces) >= 2
    m = plan.metrics
    assert m["goal_error"] < 1e-12
    assert m["obstacle_clearance_min"] > 0.0  # pushed out of the obstacle by the outer map
    assert m["cone_violation_max"] > 0.1  # no cone rows: the tube and the corners leave the cones
    # consecutive pushes meet; every sample belongs to a push
    assert plan.pushes[0].samples[0] == 0 and plan.pushes[-1].samples[-1] == plan.t.size - 1


def test_the_scene_radius_is_the_one_planned_for() -> None:
    """A 24 mm puck: the obstacle margin and every tool pose are for that radius (the face's contact
    point sits on the puck's rim, the tool outline clear of the puck)."""
    from tooltransfer.tools.pose import Pose2D

    tool = load_tool("slope")
    t, x = l_scene()
    obstacle = Disc(np.array([0.02, 0.1]), 0.006)
    big = 0.024
    plan = condense_qp(t, x, setting_for(tool, big, obstacles=(obstacle,)))
    assert plan.status == "solved", plan.reason
    assert plan.metrics["obstacle_clearance_min"] >= 0.005 - 1e-6
    gap = np.linalg.norm(plan.object_xy - obstacle.centre, axis=1).min() - obstacle.radius - big
    assert gap == pytest.approx(plan.metrics["obstacle_clearance_min"], abs=1e-12)
    for p in plan.pushes:
        for k in range(0, len(p.samples), 20):
            pose = Pose2D(*p.tool_pose[k])
            puck = shapely.Point(plan.object_xy[p.samples[k]]).buffer(big, quad_segs=64)
            d = shapely.distance(pose.place(tool.outline), puck)
            overlap = shapely.intersection(pose.place(tool.outline), puck).area
            assert d < 1e-4 and overlap < 1e-8  # touching, not penetrating


def test_the_friction_cone_narrows_the_face_cones() -> None:
    """The admissible cone is the friction cone's fraction about the normal, cut by the tool file's
    cone: for the slope's inclined face (normal 5 pi / 6, file cone 0.75 pi +- pi / 6)."""
    tool = load_tool("slope")
    f = tool.face("inclined")
    for frac in (0.3, 0.5, 1.0):
        fr = FaceFrame.build(setting_for(tool), "inclined", friction_cone_fraction=frac)
        half = frac * np.arctan(0.8)
        lo = max(f.normal_angle - half, f.push_angle - f.theta_b)
        hi = min(f.normal_angle + half, f.push_angle + f.theta_b)
        assert fr.push_angle - fr.theta_b == pytest.approx(lo, abs=1e-12)
        assert fr.push_angle + fr.theta_b == pytest.approx(hi, abs=1e-12)
