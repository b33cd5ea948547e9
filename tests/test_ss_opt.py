"""SS skill, the opt variant: never a penetrating path, Fig. 11 cases, impossible switches, the cache."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tooltransfer.planner.planning.ss import (
    OptOptions,
    SwitchSkill,
    SwitchTask,
    learn_switch_skill,
    optimize,
    recombine,
)
from tooltransfer.planner.planning.ss.cases import fig11_task, random_task
from tooltransfer.planner.planning.ss.synthetic import synthetic_switches
from tooltransfer.tools.clearance import swept_penetration_depth
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.model import Face, Tool
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.pose import Pose2D


@pytest.fixture(scope="module")
def skill() -> SwitchSkill:
    return learn_switch_skill(synthetic_switches(5, seed=1), virtual="arch", tool="finger")


def exact_penetration(task: SwitchTask, xy: np.ndarray, yaw: np.ndarray) -> float:
    """Largest penetration into the object and obstacles over the steps, from tooltransfer.tools.clearance."""
    poses = [Pose2D(*p, a) for p, a in zip(xy, yaw, strict=True)]
    return max(swept_penetration_depth(task.tool, a, b, s)
               for a, b in itertools.pairwise(poses) for s in (task.shape, *task.obstacles))


def check_solved(task: SwitchTask, path, tol: float) -> None:
    assert path.ok, path.reason
    a, b = task.contact("from"), task.contact("to")
    np.testing.assert_allclose(path.xy[[0, -1]], [a.pose.position, b.pose.position], atol=1e-12)
    assert exact_penetration(task, path.xy, path.yaw) <= tol
    assert np.all(joint_path(task.omni, path.xy).violation == 0.0)


@pytest.mark.parametrize("name", ["fig11a", "fig11a_stem", "fig11b"])
def test_fig11_opt_paths_do_not_penetrate(skill: SwitchSkill, name: str) -> None:
    task = fig11_task(name)
    path = optimize(skill, task)
    check_solved(task, path, 1e-4)  # the 0.1 mm
    dmp = recombine(skill, task, n_samples=40)
    print(f"{name}: opt penetration {1e3 * path.object_penetration:.4f} mm, clearance "
          f"{1e3 * path.object_clearance:.2f} mm; dmp penetration {1e3 * dmp.object_penetration:.2f} mm")


@settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), obstacle=st.booleans())
def test_opt_never_returns_a_penetrating_path(skill: SwitchSkill, seed: int, obstacle: bool) -> None:
    task = random_task(np.random.default_rng(seed), obstacle_prob=1.0 if obstacle else 0.0)
    path = optimize(skill, task)
    if path.ok:
        check_solved(task, path, 5e-6)
    else:
        assert path.status in ("infeasible", "failed") and path.reason


def test_end_contact_out_of_reach_is_infeasible(skill: SwitchSkill) -> None:
    path = optimize(skill, SwitchTask(load_tool("finger"), "upper", "left", np.array([0.0, 0.22])))
    assert path.status == "infeasible" and "end contact pose" in path.reason and "unreachable" in path.reason


def square_tool() -> Tool:
    h = 0.005
    return Tool("square", shapely.box(-h, -h, h, h), (
        Face("left", np.array([-h, h]), np.array([-h, -h]), np.pi, np.pi / 6),
        Face("right", np.array([h, -h]), np.array([h, h]), 0.0, np.pi / 6),
    ), a_t=0.026)


def test_a_tool_that_cannot_get_round_the_walls_is_infeasible(skill: SwitchSkill) -> None:
    # walls 1 mm above and below the puck, reaching beyond the Omni's reach on both sides: the
    # 10 mm square cannot pass from the puck's left to its right
    c = np.array([0.0, 0.16])
    walls = (shapely.box(-0.2, c[1] + 0.0185, 0.2, c[1] + 0.021), shapely.box(-0.2, c[1] - 0.021, 0.2, c[1] - 0.0185))
    task = SwitchTask(square_tool(), "right", "left", c, obstacles=walls)
    path = optimize(skill, task)
    assert path.status == "infeasible", path.reason
    assert "no feasible switch path" in path.reason and "violated at its last iterate" in path.reason
    # without the walls the same switch is solved
    check_solved(SwitchTask(square_tool(), "right", "left", c), optimize(skill, SwitchTask(
        square_tool(), "right", "left", c)), 5e-6)


def test_contact_pose_inside_an_obstacle_is_infeasible(skill: SwitchSkill) -> None:
    c = np.array([0.0, 0.16])
    task = SwitchTask(load_tool("finger"), "upper", "left", c, obstacles=(shapely.box(0.02, -0.01 + c[1], 0.03, c[1]),))
    path = optimize(skill, task)
    assert path.status == "infeasible" and "overlaps obstacle 0" in path.reason


def test_solver_is_reused_and_capsule_model_solves(skill: SwitchSkill) -> None:
    task = SwitchTask(load_tool("finger"), "upper", "left", np.array([0.01, 0.15]))
    first = optimize(skill, task)
    # another object position whose NLP has the same structure (the same reach rows: the cache key
    # holds them, so a position far from this one may need an NLP of its own)
    again = optimize(skill, SwitchTask(load_tool("finger"), "upper", "left", np.array([-0.01, 0.15])))
    assert again.info["attempts"][0]["reach_rows"] == first.info["attempts"][0]["reach_rows"]
    assert again.ok and not again.info["attempts"][0]["built"]
    cap = optimize(skill, task, OptOptions(model="capsule", solver="sqp"))
    check_solved(task, cap, 5e-6)


# Random switches of the benchmark (seed 0) that used to end with IPOPT's iteration limit, started
# from a dmp path 25-28 mm deep in the object ("armpit" of the T-shape), and one whose solution
# tunnelled through the object and an obstacle between two knots (8.6 mm, refinements then failed).
HARD = {
    "t_armpit_right": ("t_shape", "stem_left", "right", (0.051092, 0.1719379), 0.0364, 0.4259, ()),
    "t_armpit_top": ("t_shape", "stem_left", "top", (-0.01243079, 0.18256196), 0.106, 0.8236, ()),
    "i_tunnel": ("i_shape", "left", "right", (0.07660951, 0.17343962), 0.8473, 0.9705,
                 (((0.06555662, 0.11750425), 0.014485457526108997),)),
}


@pytest.mark.parametrize("name", sorted(HARD))
def test_hard_switches_are_solved_from_a_path_round_the_object(skill: SwitchSkill, name: str) -> None:
    from tooltransfer.tools.objects import Disc

    tool, fa, fb, c, sa, sb, obs = HARD[name]
    task = SwitchTask(load_tool(tool), fa, fb, np.array(c), s_from=sa, s_to=sb,
                      obstacles=tuple(Disc(np.array(o), r) for o, r in obs))
    assert recombine(skill, task, n_samples=40).max_penetration > 5e-3  # the dmp path goes through
    path = optimize(skill, task)
    check_solved(task, path, 5e-6)
    assert path.info["attempts"][0]["start"].startswith("round")
    steps = np.hypot(*np.diff(path.xy, axis=0).T)
    assert steps.max() < 0.5 * 2 * task.obj.radius  # no jump across the object between two knots


def test_round_paths_join_the_contacts_outside_the_c_obstacle() -> None:
    from tooltransfer.planner.planning.ss.initial import c_obstacle, round_paths

    task = fig11_task("fig11a_stem")
    a, b = task.contact("from"), task.contact("to")
    psi = 0.5 * (a.pose.yaw + b.pose.yaw)
    paths = round_paths(task.tool, a.pose.position, b.pose.position, psi, (task.shape,), 1e-3, 40)
    assert len(paths) == 2  # one each way round
    inside = c_obstacle(task.tool, psi, (task.shape,), 0.0)  # the C-obstacle without the margin
    for x in paths:
        np.testing.assert_allclose(x[[0, -1]], [a.pose.position, b.pose.position], atol=0)
        assert not shapely.contains_xy(inside, x[1:-1, 0], x[1:-1, 1]).any()
    # the two ways round differ: one goes by each side of the object
    d = b.pose.position - a.pose.position
    side = [np.sign(d[0] * (x[20] - a.pose.position)[1] - d[1] * (x[20] - a.pose.position)[0]) for x in paths]
    assert side[0] != side[1]


@pytest.mark.parametrize("separators", ["angle", "vector", "distance"])
def test_every_separator_form_solves_the_fig11_cases(skill: SwitchSkill, separators: str) -> None:
    for name in ("fig11a", "fig11b"):
        task = fig11_task(name)
        check_solved(task, optimize(skill, task, OptOptions(separators=separators)), 1e-4)


@pytest.mark.parametrize(("field", "value"), [("init", "nope"), ("max_starts", 0), ("step_factor", -1.0),
                                              ("min_step", float("nan")), ("body_band", -0.01),
                                              ("reach_band", float("inf")), ("separators", "polar")])
def test_bad_options_raise_input_error(skill: SwitchSkill, field: str, value: object) -> None:
    from tooltransfer.errors import InputError

    with pytest.raises(InputError, match=field):
        optimize(skill, fig11_task("fig11b"), OptOptions(**{field: value}))


def test_polygon_object_with_disc_and_polygon_obstacles(skill: SwitchSkill) -> None:
    """Mixed bodies under the default rows: the square object and a square obstacle keep their
    separating variables, the disc obstacle gets signed-distance rows; the path does not penetrate."""
    from tooltransfer.tools.objects import Disc, PolygonObject

    c = np.array([0.0, 0.16])
    square = PolygonObject(shapely.box(-0.015, -0.015, 0.015, 0.015))
    task = SwitchTask(load_tool("finger"), "upper", "left", c, obj=square,
                      obstacles=(Disc(c + np.array([0.055, 0.02]), 0.01), shapely.box(-0.075, 0.17, -0.06, 0.185)))
    # the upper face meets the square flush (its heading iteration alternates between two corners):
    # the contact has the Omni's heading at its position and touches without overlap
    from tooltransfer.planner.planning.ss.verify import pose_depth_and_gap
    from tooltransfer.tools.omni.heading import heading

    a = task.contact("from")
    assert abs(heading(task.omni, a.pose.position)[0] - a.pose.yaw) < 1e-12
    assert pose_depth_and_gap(task.tool, a.pose, task.shape) == (0.0, 0.0)
    path = optimize(skill, task)
    check_solved(task, path, 5e-6)
    assert path.obstacle_penetration <= 5e-6
