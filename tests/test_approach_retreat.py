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
