"""A fit whose contact keeps to a window of a face writes its cone rows in the frame of that window (its
pushes are measured at their own poses): the tool's heading follows where the contact is, by degrees along
a long face."""

from __future__ import annotations

import numpy as np
import pytest
from test_verdicts import generated

from tooltransfer.planner.planning.oe.contacts import realise_span, usable_range
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.oe.guided_moves import contact_windows
from tooltransfer.planner.planning.oe.metrics import window_frame
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.sequence_fit import fit_frame
from tooltransfer.planner.planning.setting import Setting, setting_from_task, task_skills
from tooltransfer.planner.planning.solve import qp_options
from tooltransfer.problems.task import Task


@pytest.fixture(scope="module")
def world() -> tuple[Task, Setting, QPOptions]:
    task = generated("verdicts_200.yaml", "verd200-00059")  # an L-shaped tool: foot_top is 34 mm long
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    return task, setting, qp_options(task).model_copy(update={"contact_span": 0.004})


def test_without_a_window_the_fit_s_frame_is_the_face_s_middle(world) -> None:
    task, setting, _ = world
    plain = qp_options(task)
    for face in setting.tool.face_names:
        got = fit_frame(setting, face, plain)
        want = FaceFrame.build(setting, face, friction_cone_fraction=plain.friction_cone_fraction)
        assert np.array_equal(got.centre_in_tool, want.centre_in_tool) and np.array_equal(got.base, want.base)
        assert {k: v for k, v in vars(got).items() if k not in ("centre_in_tool", "base")} == {
            k: v for k, v in vars(want).items() if k not in ("centre_in_tool", "base")}


def test_a_window_toward_one_end_turns_the_frame_by_more_than_the_cone_check_allows(world) -> None:
    """foot_top's last window: the frame's contact is at the window's middle; with the puck in the same
    place the tool's heading differs from the face middle's by more than the cone check's 0.01 rad, and
    :func:`window_frame` gives the same frame from the middle one."""
    task, setting, options = world
    face = "foot_top"
    lo, hi = contact_windows(setting.tool, face, options)[-1]
    windowed = options.model_copy(update={"contact_windows": {face: (lo, hi)}})
    frame, middle = fit_frame(setting, face, windowed), fit_frame(setting, face, options)
    assert frame.s == pytest.approx(0.5 * (lo + hi))
    assert (frame.push_angle, frame.theta_b) == (middle.push_angle, middle.theta_b)  # the same cone on the tool
    p = np.array(task.start)[None]
    assert abs(float(frame.heading(p)[0] - middle.heading(p)[0])) > 0.01
    again = window_frame(middle, setting, frame.s)
    assert np.allclose(again.centre_in_tool, frame.centre_in_tool) and again.offset == pytest.approx(frame.offset)
    assert again.reach == pytest.approx(frame.reach) and again.theta_b == middle.theta_b


def test_a_push_on_a_window_says_which_frame_it_was_fitted_in(world) -> None:
    task, setting, options = world
    face = "foot_top"
    window = contact_windows(setting.tool, face, options)[-1]
    windowed = options.model_copy(update={"contact_windows": {face: window}})
    frame = fit_frame(setting, face, windowed)
    t = np.linspace(0.0, 1.0, 41)
    way = frame.push_direction(np.array(task.start)[None])[0]
    x = np.array(task.start) + np.outer(t * 0.004, [np.cos(way), np.sin(way)])
    pushes = realise_span(setting, face, t, x, np.arange(t.size), windowed)
    assert pushes and all(p.frame_s == pytest.approx(frame.s) for p in pushes)
    lo, hi = usable_range(setting.tool, face, windowed)
    assert all(lo - 1e-6 <= p.contact_s.min() and p.contact_s.max() <= hi + 1e-6 for p in pushes)
    plain = realise_span(setting, face, t, x, np.arange(t.size), options)
    assert all(np.isnan(p.frame_s) for p in plain)


def _edge_pushes(world):
    """Pushes of foot_top on its last window along either edge of that window's cone (2 mm from the
    task's start, 41 samples over 1 s): for each side, the way [rad], the path ``x`` and velocity ``v``
    (41, 2) and the realised pushes; with the sample times and the face middle's frame."""
    task, setting, options = world
    face = "foot_top"
    window = contact_windows(setting.tool, face, options)[-1]
    windowed = options.model_copy(update={"contact_windows": {face: window}})
    frame, middle = fit_frame(setting, face, windowed), fit_frame(setting, face, options)
    start = np.array(task.start)
    t = np.linspace(0.0, 1.0, 41)
    sides = []
    for side in (-1.0, 1.0):  # the edge where the middle's cone is narrower is one of them
        way = float(frame.push_direction(start[None])[0]) + side * 0.98 * frame.theta_b
        x = start + np.outer(t * 0.002, [np.cos(way), np.sin(way)])
        v = np.tile(0.002 * np.array([np.cos(way), np.sin(way)]), (t.size, 1))
        sides.append((way, x, v, realise_span(setting, face, t, x, np.arange(t.size), windowed)))
    return t, middle, sides


def test_a_push_on_a_window_is_measured_at_its_own_poses(world) -> None:
    """A push along the edge of foot_top's last window's cone: measured at the tool's yaw of its own
    poses (the frame it was fitted in, ``frame_s``, no longer matters), inside the cone to within the
    check's 0.01 rad; at the face middle's heading it would be outside by more than that."""
    from dataclasses import replace as changed

    from tooltransfer.planner.planning.oe.constraints import HeadingCone
    from tooltransfer.planner.planning.oe.metrics import plan_metrics
    from tooltransfer.planner.planning.oe.push_plan import PushPlan
    from tooltransfer.tools.pose import wrap_angle

    setting = world[1]
    t, middle, sides = _edge_pushes(world)
    at_middle = []
    for way, x, v, pushes in sides:
        plan = PushPlan("qp", "solved", t, x, v, x, pushes=tuple(pushes))
        frames = {"foot_top": middle}
        got = plan_metrics(plan, frames, x[-1], setting)["cone_violation_max"]
        plain = plan_metrics(changed(plan, pushes=tuple(changed(p, frame_s=float("nan")) for p in pushes)),
                             frames, x[-1], setting)["cone_violation_max"]
        yaw = np.concatenate([p.tool_pose[:, 2] for p in pushes])
        want = max(0.0, float((np.abs(wrap_angle(way - yaw - middle.push_angle)) - middle.theta_b).max()))
        assert got == plain == pytest.approx(want, abs=1e-12)
        assert got <= 0.01
        at_middle.append(HeadingCone(middle).angle_violation(x, v, 1e-3))
    assert max(at_middle) > 0.01


def test_a_push_without_poses_is_measured_in_the_frame_it_was_fitted_in(world) -> None:
    """The fallback of the cone check: a push that carries no tool poses for its samples is measured at
    the heading of its window's frame (``frame_s``), where a velocity along that frame's cone edge is
    inside, and the face middle's frame would see it outside."""
    from dataclasses import replace as changed

    from tooltransfer.planner.planning.oe.constraints import HeadingCone
    from tooltransfer.planner.planning.oe.metrics import plan_metrics, window_frame
    from tooltransfer.planner.planning.oe.push_plan import PushPlan

    setting = world[1]
    t, middle, sides = _edge_pushes(world)
    at_middle = []
    for _, x, v, pushes in sides:
        bare = tuple(changed(p, tool_pose=np.zeros((0, 3))) for p in pushes)
        plan = PushPlan("qp", "solved", t, x, v, x, pushes=bare)
        got = plan_metrics(plan, {"foot_top": middle}, x[-1], setting)["cone_violation_max"]
        at = window_frame(middle, setting, pushes[0].frame_s)
        assert got == pytest.approx(HeadingCone(at).angle_violation(x, v, 1e-3), abs=1e-12)
        assert got <= 1e-3
        at_middle.append(HeadingCone(middle).angle_violation(x, v, 1e-3))
    assert max(at_middle) > 0.01
