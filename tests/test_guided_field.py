"""The distance field that orders the guided search's last attempts
(:mod:`~tooltransfer.planner.planning.oe.guided_field`): its paths go round what the puck may not
cross and only where some face pushes, cells it cannot connect to the target come last, and ordered
by it the search finds a path the straight line's order runs out of expansions on."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from guided_ladder import executed_plan_of, ladder_plans
from test_verdicts import generated

from tooltransfer.planner.planning.oe.guided import (
    CELL,
    FINE,
    STEP,
    GuidedMiss,
    GuidedPath,
    guide_field,
    guided_path,
)
from tooltransfer.planner.planning.oe.guided_field import UNREACHED, distance_field
from tooltransfer.planner.planning.oe.guided_rungs import GREED, LAST_ROOM, _ladder
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import qp_options

TARGET = np.array([0.0, 0.0])
START = np.array([0.08, 0.0])
WALL = shapely.box(0.035, -0.03, 0.045, 0.10)  # a wall across the straight line, open below its lower end


def _free(q: np.ndarray) -> bool:
    return not shapely.intersects_xy(WALL, float(q[0]), float(q[1]))


def _any_way(p: np.ndarray, every: bool = False) -> list[tuple[str, float, float]]:
    """One face that pushes in every direction, everywhere."""
    return [("all", 0.0, math.pi)]


def test_the_field_goes_round_what_the_puck_may_not_cross() -> None:
    """With a face that pushes anywhere, the field is the length of the shortest way round the wall:
    from the start, down past the wall's lower end and back up to the target, never shorter than that
    way (the grid's moves are straight lines between cell centres, the way's corners are the wall's) and
    at most a few per cent longer (moves of up to three cells: directions 7-18 degrees apart)."""
    cell = 0.002
    field = distance_field(_any_way, _free, START, TARGET, 3 * cell, cell)
    corners = [np.array([0.045, -0.03]), np.array([0.035, -0.03])]
    way = (np.hypot(*(corners[0] - START)) + np.hypot(*(corners[1] - corners[0]))
           + np.hypot(*(TARGET - corners[1])))
    got = field.to_go(START)
    assert way - 2 * cell <= got <= 1.05 * way + 2 * cell
    assert got > np.hypot(*(TARGET - START)) + 0.01  # not the straight line through the wall
    assert field.to_go(np.array([0.04, 0.05])) == UNREACHED  # inside the wall: no path
    assert field.to_go(TARGET) < cell


def test_cells_no_face_pushes_the_target_from_come_last() -> None:
    """A face that pushes only toward -x (within 20 degrees): the target is reached from cells on its
    +x side, at about their distance, and from none on its -x side or straight above it (every move's x
    falls); those are ordered at :data:`UNREACHED`, after every reachable cell, and outside the grid
    further still."""
    half = math.radians(20)

    def toward_minus_x(p: np.ndarray, every: bool = False) -> list[tuple[str, float, float]]:
        return [("left", math.pi, half)]

    cell = 0.002
    field = distance_field(toward_minus_x, lambda q: True, START, TARGET, 3 * cell, cell)
    assert field.to_go(np.array([0.05, 0.0])) == pytest.approx(0.05, abs=2 * cell)
    assert field.to_go(np.array([0.05, 0.01])) == pytest.approx(np.hypot(0.05, 0.01), rel=0.05, abs=2 * cell)
    assert field.to_go(np.array([-0.03, 0.0])) == UNREACHED
    assert field.to_go(np.array([0.0, 0.04])) == UNREACHED  # every move's x falls: never straight above
    # the relaxation at the grid's resolution: a move is widened by the angle the cell subtends over it
    # (26 degrees on a one-cell diagonal), so 45 degrees off the cone's middle counts as a push there
    assert field.to_go(np.array([0.03, 0.03])) == pytest.approx(np.hypot(0.03, 0.03), abs=2 * cell)
    assert field.to_go(np.array([1.0, 0.0])) > UNREACHED


def test_in_the_field_s_order_the_search_finds_a_path_the_straight_line_s_order_runs_out_on() -> None:
    """exec60-00033 (t_shape, one obstacle), at 0.8 of the friction cone on whole faces, fine steps with
    half steps and new runs, weighted toward the target and the tool kept LAST_ROOM from the obstacle: in
    the straight line's order the search spends its 8000 expansions; in the field's order it finds a
    path, within them."""
    task = generated("execution_60.yaml", "exec60-00033")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8})
    kw = dict(options=options, more=True, step=FINE * STEP, cell=FINE * CELL, greed=GREED, room=LAST_ROOM,
              budget=round(options.guided_budget / FINE))
    start, target = np.array(task.start), np.array(task.target)
    miss = guided_path(setting, start, target, **kw)
    assert isinstance(miss, GuidedMiss) and not miss.exhausted
    order = guide_field(setting, start, target, options=options, step=FINE * STEP, room=LAST_ROOM)
    found = guided_path(setting, start, target, guide=order, **kw)
    assert isinstance(found, GuidedPath)
    assert np.allclose(found.xy[0], start) and np.allclose(found.xy[-1], target)


def test_a_task_only_the_field_s_order_solves_gets_a_plan_that_executes() -> None:
    """verd200-00002 (trapezoid, one obstacle): every attempt of the ladder before the last fails (the
    task was ``unknown``); the last, on every face's windows in the field's order, gives a plan that
    passes every hard check, records that it came from there, and ends within 5 mm of the target open
    loop on the MuJoCo platform."""
    executed_plan_of(generated("verdicts_200.yaml", "verd200-00002"), "guided_field")


def test_the_field_s_order_on_whole_faces_gives_a_plan_that_executes() -> None:
    """exec60-00033 (t_shape, one obstacle): every attempt before the field's fails; the field's first form, on whole
    faces and their windows only where the whole is not held, gives a plan that passes every hard check and ends
    within 5 mm of the target open loop on the MuJoCo platform. Before that form, the field's attempt on every face's
    windows found none, and the plan came after it, from the weighted search made again (``guided_spent``, 34
    pushes), and ended 27.5 mm from the target open loop (benchmarks/README.md, "The guide attempt in both forms")."""
    plan = executed_plan_of(generated("execution_60.yaml", "exec60-00033"), "guided_field")
    assert "guided_narrow" not in plan.metrics and "guided_close" not in plan.metrics


def test_the_field_s_attempts_come_last_and_not_after_a_plan_is_kept() -> None:
    """exec60-00054 (l_shape, one obstacle; the push plans of its attempts on windows fit, the switches
    between their faces do not, and after the search it is certified ``switch_separated``): the ladder
    ends with the two attempts in the field's order, first on whole faces and their windows where the whole is not
    held, then on every face's windows, then the narrow windows' attempt (tests/test_guided_narrow.py) and the
    closest attempt (tests/test_guided_close.py); where the caller keeps a plan of an attempt before (one with little
    room), it makes none of them: they are there for tasks with no plan at all."""
    task = generated("execution_60.yaml", "exec60-00054")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task)
    guides = [r for r in _ladder(setting, options) if r.guide]
    assert [(r.windows, r.mixed) for r in guides] == [(False, options.guided_contact_span), (True, None)]
    every = ladder_plans(task, keep_after_first=False)
    field = [k for k, p in enumerate(every) if p.metrics.get("guided_field")
             or "over a grid of where the faces push" in p.reason]
    assert field == [len(every) - 4, len(every) - 3]
    for p in every[-4:-2]:  # both fit; their switches then fail
        assert p.status == "solved" and p.metrics["guided_field"] == 1.0
    assert every[-2].metrics.get("guided_narrow") == 1.0 or "on its 2 mm windows" in every[-2].reason
    assert every[-1].metrics.get("guided_close") == 1.0 or "each step ending where its face holds" in every[-1].reason
    kept = ladder_plans(task, keep_after_first=True)
    assert [(p.status, p.reason) for p in kept] == [(p.status, p.reason) for p in every[:-4]]


def test_a_miss_says_where_the_field_found_no_way_either() -> None:
    """verd200-00049 (l_shape, one obstacle, unknown), searched as the ladder's last attempt (every face
    on its 4 mm windows, 0.8 of the cone, fine steps, the tool LAST_ROOM from the obstacle): the search
    finds no path, and its field connects no way from the start to the target's funnel either, which the
    miss says; a search in the straight line's order says nothing of a field."""
    task = generated("verdicts_200.yaml", "verd200-00049")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8,
                                                  "contact_span": qp_options(task).guided_contact_span})
    kw = dict(options=options, windows=True, more=True, step=FINE * STEP, cell=FINE * CELL, greed=GREED,
              room=LAST_ROOM, budget=round(options.guided_budget / FINE))
    start, target = np.array(task.start), np.array(task.target)
    order = guide_field(setting, start, target, options=options, step=FINE * STEP, windows=True, room=LAST_ROOM)
    assert order.to_go(start) == UNREACHED
    miss = guided_path(setting, start, target, guide=order, **kw)
    assert isinstance(miss, GuidedMiss) and miss.unguided
    assert "its distance field found no way from the start to the target either" in miss.describe()
    plain = guided_path(setting, start, target, **kw)
    assert isinstance(plain, GuidedMiss) and not plain.unguided and "distance field" not in plain.describe()
