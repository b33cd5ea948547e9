"""The approach and the retreat of a plan: the tool backs off from the first and last contacts along the
face's normal where the Omni reaches and nothing is in the way, else a little obliquely."""

from __future__ import annotations

import math

import numpy as np
import shapely

from tooltransfer.planner.planning.assemble import _reachable_back
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.problems.task import load_task
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.pose import rotation


def _bodies(setting, at: np.ndarray, offset: np.ndarray) -> list[shapely.Polygon]:
    """The tool outline along the straight move from ``at`` by ``offset`` [m], at the Omni's headings."""
    line = at + np.linspace(0.0, 1.0, 40)[:, None] * offset
    jp = joint_path(setting.platform, line)
    assert np.all(jp.violation == 0.0)  # within the Omni's reach and joint limits all along
    ring = np.asarray(setting.tool.outline.exterior.coords)
    return [shapely.Polygon(ring @ rotation(h).T + p) for p, h in zip(line, jp.heading, strict=True)]


def test_the_back_off_turns_aside_where_the_straight_one_would_hit_an_obstacle() -> None:
    task = load_task("paper/transfer_tool2")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    face = setting.tool.faces[0]
    x, y, yaw = FaceFrame.build(setting, face.name).tool_pose(np.array(task.start)[None])[0]
    at = np.array([x, y])
    normal = rotation(yaw) @ face.normal
    direction = math.atan2(normal[1], normal[0])
    straight = _reachable_back(setting.platform, at, direction, 0.01)
    assert np.allclose(straight, -0.01 * normal)  # nothing in the way: the whole distance along the normal
    # a small obstacle 1.5 mm behind the tool's body: any straight back-off of 2 mm or more hits it
    body = np.asarray(_bodies(setting, at, np.zeros(2))[0].exterior.coords)
    far = body[np.argmax(body @ -normal)]
    obstacle = Disc(tuple(far - 0.0023 * normal), 0.0008)
    assert shapely.distance(_bodies(setting, at, np.zeros(2))[0], obstacle.polygon()) > 0.001
    assert any(b.intersects(obstacle.polygon()) for b in _bodies(setting, at, straight))
    aside = _reachable_back(setting.platform, at, direction, 0.01, setting.tool, [obstacle])
    assert np.linalg.norm(aside) >= 0.002 and not np.allclose(aside / np.linalg.norm(aside), -normal)
    centre = shapely.Point(obstacle.centre)
    assert all(shapely.distance(b, centre) > obstacle.radius for b in _bodies(setting, at, aside))


def test_at_the_edge_of_the_workspace_the_back_off_comes_in_along_the_face() -> None:
    """A contact pose 1.2 mm inside the Omni's outer reach, its face's normal pointing at the Omni's axis
    (backing off straight leaves the reach): no back-off of 2 mm turned up to 40 degrees stays within the
    joint limits, one turned 60 degrees does, and that is the one taken (a wide turn needs the tool and
    the resting puck, to keep the one off the other)."""
    from tooltransfer.planner.planning.assemble import BACK_OFF_TURNS, WIDE_TURNS

    task = load_task("paper/transfer_tool2")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    base = FaceFrame.build(setting, setting.tool.faces[0].name).base
    out = np.array(task.start) - base
    out /= np.linalg.norm(out)

    def inside(r: float) -> bool:
        return bool(joint_path(setting.platform, (base + r * out)[None]).violation[0] == 0.0)

    lo, hi = np.linalg.norm(np.array(task.start) - base), 1.0
    assert inside(lo) and not inside(hi)
    for _ in range(60):  # the outer reach along the ray, by bisection
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if inside(mid) else (lo, mid)
    at = base + (lo - 0.0012) * out
    direction = math.atan2(-out[1], -out[0])  # backing off straight goes out

    def fits(turn: float) -> bool:
        u = -np.array([math.cos(direction + turn), math.sin(direction + turn)])
        line = at + np.linspace(0.0, 0.002, 20)[:, None] * u
        return bool(np.all(joint_path(setting.platform, line).violation == 0.0))

    assert not any(fits(turn) for turn in BACK_OFF_TURNS)
    assert any(fits(turn) for turn in WIDE_TURNS)
    assert np.allclose(_reachable_back(setting.platform, at, direction, 0.01), -0.002 * np.array(
        [math.cos(direction), math.sin(direction)]))  # without the tool and the puck: no wide turn, the last resort
    far = Disc(tuple(at + 0.5 * out), 0.0175)  # a puck well away: this is about the reach
    back = _reachable_back(setting.platform, at, direction, 0.01, setting.tool, puck=far)
    assert np.linalg.norm(back) >= 0.002 - 1e-12
    line = at + np.linspace(0.0, 1.0, 40)[:, None] * back
    assert np.all(joint_path(setting.platform, line).violation == 0.0)
    turned = math.degrees(math.acos(float(back @ out) / float(np.linalg.norm(back))))
    assert 59.0 <= turned <= 76.0  # away from the contact's normal by a wide turn, still backing off


def test_a_plan_whose_approach_is_turned_wide_keeps_the_tool_off_the_resting_puck() -> None:
    """verd200-00056 (slope, no obstacle): its first contact lies at the edge of the Omni's workspace, where
    only a wide turn keeps the approach within the joint limits; along the approach the tool's outline
    keeps off the resting puck until the contact, and the plan passes every hard check."""
    from test_verdicts import generated

    from tooltransfer.planner.planning.solve import hard_check_failures, solve

    task = generated("verdicts_200.yaml", "verd200-00056")
    plan = solve(task)
    assert plan.status == "solved" and hard_check_failures(plan.metrics) == []
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    k = np.flatnonzero(np.array(plan.phase) == "approach")
    pose, puck = plan.tool_pose[k], plan.object_xy[k[0]]
    move = pose[-1, :2] - pose[0, :2]
    face = setting.tool.face(plan.face[k[-1] + 1])
    normal = rotation(float(pose[-1, 2])) @ face.normal
    turned = math.degrees(math.acos(float(move @ normal) / float(np.linalg.norm(move))))
    assert turned >= 59.0  # not along the normal, nor 20 or 40 degrees from it: those leave the joint limits
    ring = np.asarray(setting.tool.outline.exterior.coords)
    gaps = [shapely.distance(shapely.Polygon(ring @ rotation(float(h)).T + xy), shapely.Point(puck)) - setting.radius
            for xy, h in zip(pose[:-1, :2], pose[:-1, 2], strict=True)]
    assert min(gaps) >= -1e-6
