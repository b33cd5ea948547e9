"""The guided search's closest attempt (:mod:`tooltransfer.planner.planning.oe.guided_close`, the ladder's last
rung): the tool 0.4 mm from the obstacles at its nodes, windows of 1 mm, and every step ending where its own face
still holds the puck (shrunk to a half or a quarter where the whole does not)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from guided_ladder import executed_plan_of
from test_verdicts import contact_pose, generated

from tooltransfer.planner.planning.oe.contacts import MIN_PIECE, usable_range
from tooltransfer.planner.planning.oe.guided import FINE, STEP, GuidedPath, guided_path
from tooltransfer.planner.planning.oe.guided_close import CLOSE_ROOM
from tooltransfer.planner.planning.oe.guided_rungs import CLOSE, GREED, NARROW_WINDOWS, _ladder
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import qp_options
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.reach import reach_sector
from tooltransfer.tools.pushing.inverse import contact_path


def _clearance(setting, face, s: float, p: np.ndarray) -> float | None:
    """The tool outline's distance [m] from the obstacles with ``face``'s contact at arc length ``s`` [m] holding
    the puck at ``p`` (2,) [m], the tool placed by the test suite's own reach sector (:func:`contact_pose` of
    ``test_verdicts``); None where the Omni does not reach it there."""
    pose = contact_pose(reach_sector(setting.platform), face, p, setting.radius, s / face.length)
    if pose is None:
        return None
    c = face.point(s / face.length) + setting.radius * face.normal
    yaw = pose[0] - math.pi / 2
    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    outline = shapely.Polygon((np.asarray(setting.tool.outline.exterior.coords) - c) @ rot.T + p)
    return min(float(shapely.distance(outline, o.polygon() if isinstance(o, Disc) else o)) for o in setting.obstacles)


def test_the_closest_attempt_is_the_ladder_s_last_and_made_only_for_a_task_with_no_plan() -> None:
    """The rung: the middle share of the friction cone, fine steps, windows of :data:`CLOSE` of
    ``guided_contact_span`` where the whole face is not held, :data:`CLOSE_ROOM`, and one of the last attempts
    (not made after a plan kept with little room)."""
    task = generated("verdicts_200.yaml", "verd200-00120")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task)
    rungs = _ladder(setting, options)
    last = rungs[-1]
    assert last.close and last.last and not any(r.close for r in rungs[:-1])
    assert last.mixed == pytest.approx(CLOSE * options.guided_contact_span) and last.room == CLOSE_ROOM
    assert last.fine and last.more and last.most == NARROW_WINDOWS and last.greed == GREED
    assert last.change == {"friction_cone_fraction": 0.8}


def test_every_step_of_the_closest_attempt_ends_where_its_face_holds_the_puck() -> None:
    """On verd200-00120 (finger, one obstacle; ``unknown`` before this attempt) the search finds a path. At both
    ends of every step, the step's face holds the puck at both ends of its contact window (or of its usable range,
    a face held as a whole): the Omni reaches it (the test suite's own reach sector) and the tool outline keeps
    :data:`CLOSE_ROOM` from the obstacle. Its steps are whole, half or quarter fine steps, and none rolls the
    contact faster than its window's width per ``MIN_PIECE`` of travel (by the inverse push model's rolling)."""
    task = generated("verdicts_200.yaml", "verd200-00120")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    base = qp_options(task)
    options = base.model_copy(update={"friction_cone_fraction": 0.8})
    found = guided_path(setting, np.array(task.start), np.array(task.target), options=options,
                        step=FINE * STEP, cell=FINE * 0.002, budget=16000, more=True,
                        mixed=CLOSE * base.guided_contact_span, greed=GREED, room=CLOSE_ROOM, most=NARROW_WINDOWS,
                        close=True)
    assert isinstance(found, GuidedPath)
    faces = {f.name: f for f in setting.tool.faces}
    sizes = set()
    for k, (name, window) in enumerate(zip(found.faces, found.windows, strict=True)):
        face = faces[name]
        lo, hi = window if window is not None else usable_range(setting.tool, name, options)
        for p in found.xy[k:k + 2]:
            for s in (lo, hi):
                room = _clearance(setting, face, s, p)
                assert room is not None and room >= CLOSE_ROOM - 1e-5, (k, name, s, room)
        if k == len(found.faces) - 1:
            continue  # the last straight step to the target is the finishing push's, not the attempt's
        size = float(np.hypot(*(found.xy[k + 1] - found.xy[k])))
        sizes.add(round(size / (FINE * STEP), 6))
        x = np.linspace(found.xy[k], found.xy[k + 1], 21)
        travel = contact_path(setting.tool, name, x, setting.radius, setting.mechanics, 0.5 * (lo + hi),
                              platform=setting.platform)
        rolled = float(np.ptp(travel))
        assert rolled <= (hi - lo) * size / MIN_PIECE, (k, name, rolled, size)
    assert sizes <= {1.0, 0.5, 0.25} and 1.0 in sizes


def test_a_task_only_the_closest_attempt_solves_gets_a_plan_that_passes_every_hard_check() -> None:
    """verd200-00120 was ``unknown``: every attempt before ends without a whole plan; the closest attempt's plan
    passes every hard check (the tool at least ``TOOL_MARGIN`` from the obstacle all along) and ends within 5 mm of
    the target open loop on the MuJoCo platform."""
    plan = executed_plan_of(generated("verdicts_200.yaml", "verd200-00120"), "guided_close")
    assert plan.metrics["guided_step"] == pytest.approx(FINE * STEP)
    assert plan.metrics["alternatives_tried"] >= 8  # the candidates and the ladder's attempts before it
