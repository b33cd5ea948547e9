"""Where a candidate's pushes already put the tool into an obstacle, the reason names that first: its
switches failing there too is a consequence, not the cause."""

from __future__ import annotations

import numpy as np
from test_verdicts import generated

from tooltransfer.planner.planning.solve import solve
from tooltransfer.planner.planning.tool_clearance import tool_obstacle_clearance


def test_a_push_into_an_obstacle_is_the_reason_before_its_switch() -> None:
    """verd200-00049 (l_shape, one obstacle): at the start only `foot_top` and `foot_end` reach the puck,
    and `foot_top`'s tool outline overlaps the obstacle there; every scored candidate starts with it."""
    task = generated("verdicts_200.yaml", "verd200-00049")
    plan = solve(task)
    assert plan.status != "solved"
    assert plan.reason.startswith("tool-obstacle collision: the tool outline overlaps obstacles[0] at t = 0.00 s "
                                  "(push of 'foot_top'; tool at ")
    assert "its switch foot_top -> " in plan.reason
    # independently: with the puck at the start, foot_top's tool overlaps the obstacle wherever its contact is
    from tooltransfer.planner.planning.oe.face_frame import FaceFrame
    from tooltransfer.planner.planning.setting import setting_from_task, task_skills

    setting = setting_from_task(task, task_skills(task, need_ss=False))
    s0, s1 = setting.tool.face("foot_top").contact_range
    for q in np.linspace(s0, s1, 9):
        pose = FaceFrame.build(setting, "foot_top", s=float(q)).tool_pose(np.array(task.start)[None])
        assert tool_obstacle_clearance(setting.tool, pose, list(setting.obstacles)).distance == 0.0
