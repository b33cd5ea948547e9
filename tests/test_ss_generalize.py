"""SS skill, the dmp variant: contacts at both ends, exact penetration reports, impossible switches."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from tooltransfer.planner.planning.ss import SwitchSkill, SwitchTask, learn_switch_skill, recombine
from tooltransfer.planner.planning.ss.cases import fig11_task
from tooltransfer.planner.planning.ss.synthetic import synthetic_switches
from tooltransfer.tools.clearance import swept_penetration_depth
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.pose import Pose2D


@pytest.fixture(scope="module", params=["arch", "line"])
def skill(request: pytest.FixtureRequest) -> SwitchSkill:
    return learn_switch_skill(synthetic_switches(5, seed=1), virtual=request.param, tool="finger")


def exact_penetration(task: SwitchTask, xy: np.ndarray, yaw: np.ndarray) -> float:
    """Largest penetration over the steps, from tooltransfer.tools.clearance (independent of
    tooltransfer.planner.planning.ss.verify)."""
    poses = [Pose2D(*p, a) for p, a in zip(xy, yaw, strict=True)]
    return max(swept_penetration_depth(task.tool, a, b, task.shape) for a, b in itertools.pairwise(poses))


@pytest.mark.parametrize(("tool", "fa", "fb"), [("finger", "upper", "left"), ("t_shape", "left", "top"),
                                                 ("trapezoid", "left", "inclined"), ("l_shape", "top", "foot_end")])
def test_path_starts_and_ends_at_the_contact_poses(skill: SwitchSkill, tool: str, fa: str, fb: str) -> None:
    task = SwitchTask(load_tool(tool), fa, fb, np.array([0.02, 0.16]), s_from=0.3)
    path = recombine(skill, task, n_samples=60)
    assert path.ok, path.reason
    a, b = task.contact("from"), task.contact("to")
    np.testing.assert_allclose(path.xy[0], a.pose.position, atol=1e-12)
    np.testing.assert_allclose(path.xy[-1], b.pose.position, atol=1e-12)
    np.testing.assert_allclose([path.yaw[0], path.yaw[-1]], [a.pose.yaw, b.pose.yaw], atol=1e-12)
    assert path.info["end_correction"] < 1e-4  # the DMP itself nearly reached its goal


@pytest.mark.parametrize("name", ["fig11a", "fig11a_stem", "fig11b"])
def test_fig11_dmp_paths_report_their_penetration_exactly(skill: SwitchSkill, name: str) -> None:
    task = fig11_task(name)
    path = recombine(skill, task, n_samples=40)
    assert path.ok
    ref = exact_penetration(task, path.xy, path.yaw)
    assert path.object_penetration == pytest.approx(ref, abs=2e-5)
    print(f"{name} ({skill.virtual}): dmp penetration {1e3 * path.object_penetration:.2f} mm")


def test_the_demonstrated_switch_is_reproduced_without_penetration(skill: SwitchSkill) -> None:
    demo = synthetic_switches(1, seed=11)[0]
    task = SwitchTask(load_tool("finger"), "upper", "left", demo.centre, duration=demo.duration)
    path = recombine(skill, task, n_samples=demo.t.size)
    rms = float(np.sqrt(np.mean(np.sum((path.xy - demo.xy) ** 2, axis=1))))
    assert rms < 3e-3
    assert path.object_penetration < 1e-6


def test_unreachable_end_contact_is_infeasible_with_the_reason(skill: SwitchSkill) -> None:
    task = SwitchTask(load_tool("finger"), "upper", "left", np.array([0.0, 0.22]))
    path = recombine(skill, task)
    assert path.status == "infeasible"
    assert "end contact pose" in path.reason and "unreachable" in path.reason


def test_cached_linear_map_equals_fit_and_rollout(skill: SwitchSkill) -> None:
    # tooltransfer.planner.planning.ss.recombination: the fit of f^o and the rollout as one linear map per grid
    rng = np.random.default_rng(3)
    for tool, fa, fb in [("finger", "upper", "left"), ("t_shape", "left", "top"), ("trapezoid", "left", "inclined")]:
        task = SwitchTask(load_tool(tool), fa, fb, np.array([rng.uniform(-0.03, 0.03), rng.uniform(0.14, 0.18)]))
        for n in (40, 77):
            fast = recombine(skill, task, n_samples=n, fast=True)
            slow = recombine(skill, task, n_samples=n, fast=False)
            np.testing.assert_allclose(fast.info["x_contact_point"], slow.info["x_contact_point"], rtol=0, atol=1e-14)
            np.testing.assert_allclose(fast.xy, slow.xy, rtol=0, atol=1e-14)
            assert fast.object_penetration == pytest.approx(slow.object_penetration, abs=1e-15)


def test_vectorized_disc_depths_equal_tools_clearance(skill: SwitchSkill) -> None:
    from tooltransfer.planner.planning.ss.verify import sweep_check

    for name in ("fig11a", "fig11a_stem", "fig11b"):
        task = fig11_task(name)
        path = recombine(skill, task, n_samples=40)
        fast = sweep_check(task.tool, path.xy, path.yaw, task.shape, exact_disc="union")
        slow = sweep_check(task.tool, path.xy, path.yaw, task.shape, exact_disc="substeps")
        assert fast.max_penetration > 1e-3  # these dmp paths do penetrate: the depths are exercised
        np.testing.assert_allclose(fast.depth, slow.depth, rtol=0, atol=1e-12)
        np.testing.assert_allclose(fast.gap, slow.gap, rtol=0, atol=1e-12)
