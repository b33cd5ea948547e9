"""The ``qp`` variant's guided search: where the scored candidates find no plan, a best-first search
over puck positions proposes a face sequence that the QP fit refines; the plan it gives passes every
hard check and executes on the MuJoCo platform."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from tooltransfer.planner.apps.batch.generate import generate_tasks
from tooltransfer.planner.apps.batch.spec import load_batch
from tooltransfer.planner.planning.oe.contacts import usable_range
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.oe.guided import GuidedMiss, GuidedPath, guided_path
from tooltransfer.planner.planning.oe.metrics import plan_metrics
from tooltransfer.planner.planning.oe.piecewise import fit_runs
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import HARD_CHECKS, hard_check_failures, qp_options, solve
from tooltransfer.problems.task import Task, task_from_dict
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.ik import inverse_kinematics

ROOT = Path(__file__).resolve().parents[1]
BATCH = ROOT / "problems" / "batch" / "execution_60.yaml"


def _task(task_id: str) -> Task:
    data = next(g.data for g in generate_tasks(load_batch(BATCH), BATCH) if g.task_id == task_id)
    return task_from_dict(data, str(BATCH))


def _held_at(setting, name: str, s: float, p: np.ndarray, share: float) -> tuple[bool, shapely.Polygon]:
    """Whether the Omni's inverse kinematics reaches the tool holding face ``name``'s contact ``s`` [m] along
    it with the puck at ``p`` (2,) [m], at the heading the face's frame imposes there, and the tool outline
    there [m]."""
    frame = FaceFrame.build(setting, name, s=s / setting.tool.face(name).length, friction_cone_fraction=share)
    x, y, yaw = frame.tool_pose(p[None])[0]
    ik = inverse_kinematics(setting.platform, [x, y])
    reached = bool(ik.reachable and ik.heading is not None
                   and abs(math.remainder(ik.heading - yaw, 2 * math.pi)) < 1e-6)
    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    return reached, shapely.Polygon(np.asarray(setting.tool.outline.exterior.coords) @ rot.T + [x, y])


def _room(setting, body: shapely.Polygon) -> float:
    """How far [m] ``body`` is from the nearest obstacle (infinite without one)."""
    return min((shapely.distance(body, o.polygon() if isinstance(o, Disc) else o) for o in setting.obstacles),
               default=math.inf)


def test_the_guided_path_keeps_the_rules_it_searches_under() -> None:
    task = _task("exec60-00023")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    found = guided_path(setting, np.array(task.start), np.array(task.target), options=qp_options(task))
    assert isinstance(found, GuidedPath)
    assert np.allclose(found.xy[0], task.start) and np.allclose(found.xy[-1], task.target)
    assert len(found.faces) == len(found.xy) - 1 and set(found.faces) <= set(setting.tool.face_names)
    steps = np.hypot(*np.diff(found.xy, axis=0).T)
    assert steps[:-1].max() <= 0.004 + 1e-9 and steps[-1] <= 3 * 0.004 + 1e-9  # the last: straight to the target
    # every step keeps the rules of the qp fit it proposes for, checked with the Omni's inverse
    # kinematics: both ends of the face's usable contact range reachable, the tool outline clear of
    # the obstacles, the step's direction inside the face's narrowed cone at the heading the arm imposes
    # at both of its ends
    options = qp_options(task)
    for k, name in enumerate(found.faces):
        p, d = found.xy[k], found.xy[k + 1] - found.xy[k]
        for s in usable_range(setting.tool, name, options):
            reached, body = _held_at(setting, name, s, p, options.friction_cone_fraction)
            assert reached and _room(setting, body) > 0.0
        mid = FaceFrame.build(setting, name, friction_cone_fraction=options.friction_cone_fraction)
        for end in (p, found.xy[k + 1]):  # the cone turns with the heading: inside it at both ends of the step
            off = math.remainder(math.atan2(d[1], d[0]) - mid.push_direction(end[None])[0], 2 * math.pi)
            assert abs(off) <= mid.theta_b
    t, ref, faces, switches = found.sequence(10.0)
    assert ref is found.xy
    assert t[0] == 0.0 and t[-1] == pytest.approx(10.0) and len(switches) == len(faces) - 1
    assert all(0.0 < a < b for a, b in zip(switches, [*switches[1:], 10.0], strict=True))


def test_a_task_the_candidates_miss_is_solved_by_the_guided_search_and_executes() -> None:
    pytest.importorskip("mujoco")
    from tooltransfer.planner.execution.simulate import simulate_plan

    plan = solve(_task("exec60-00023"))
    assert plan.verdict == "solved" and "time_guided" in plan.metrics
    assert all(key in plan.metrics for _, key, *_ in HARD_CHECKS)  # every hard check made, none skipped
    assert hard_check_failures(plan.metrics) == []
    assert plan.metrics["self_consistency_max"] <= 1e-4
    assert simulate_plan(plan).final_error < 0.005


def test_steps_along_either_edge_of_a_turning_cone_are_taken_and_stay_inside_it() -> None:
    """The cone turns with the heading the Omni imposes as the puck moves; a step aimed along the edge
    it turns towards ends outside it and is turned back inside. Before, it was turned back onto the edge
    itself, which the cone had again left by the step's end: every step along that edge was dropped and
    the search lost one side of each cone (here the slope's inclined face could not push up-left
    steeply enough to reach the target, which a search with both edges reaches)."""
    from tooltransfer.planner.planning.oe.guided_holds import CONE
    from tooltransfer.planner.planning.oe.guided_moves import _face_moves, _pointing, _stepped

    batch = ROOT / "problems" / "batch" / "verdicts_200.yaml"
    data = next(g.data for g in generate_tasks(load_batch(batch), batch) if g.task_id == "verd200-00011")
    task = task_from_dict(data, str(batch))
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8})
    p = np.array(task.start)
    for fm in _face_moves(setting, options):
        half = CONE * fm.cone.theta_b
        mid = FaceFrame.build(setting, fm.name, friction_cone_fraction=0.8)
        for side in (-1.0, 1.0):
            q = _stepped(fm, p, _pointing(fm, p) + side * half, half, 0.004)
            assert q is not None, f"no step along the {'lower' if side < 0 else 'upper'} edge of {fm.name}"
            d = q - p
            assert np.hypot(*d) == pytest.approx(0.004)
            for end in (p, q):  # inside the cone (the search's share of it) at both ends, by the fit's frame
                off = math.remainder(math.atan2(d[1], d[0]) - mid.push_direction(end[None])[0], 2 * math.pi)
                assert abs(off) <= half + 1e-12
            assert side * math.remainder(math.atan2(d[1], d[0]) - _pointing(fm, p), 2 * math.pi) > 0.8 * half


def _rolling_by_run(found: GuidedPath, setting, options) -> list[tuple[list[float], float]]:
    """Each run's steps' rolling of the contact along the face [m] by the project's inverse push model
    (the object pushed along the step, the contact from the middle of the usable range), with the
    usable width [m]; checked on the way against the search's own count (within 10 % + 0.1 mm)."""
    from tooltransfer.planner.planning.oe.guided_moves import _face_moves, _roll
    from tooltransfer.tools.pushing.inverse import push_tool_path

    moves = {fm.name: fm for fm in _face_moves(setting, options)}
    runs: list[tuple[list[float], float]] = []
    marks = found.runs or (0,) * len(found.faces)
    for k, name in enumerate(found.faces):
        lo, hi = usable_range(setting.tool, name, options)
        p, q = found.xy[k], found.xy[k + 1]
        model = push_tool_path(setting.tool, name, np.linspace(p, q, 9), setting.radius, setting.mechanics,
                               0.5 * (lo + hi), platform=setting.platform)
        rolls = float(model.s[-1] - model.s[0])
        searched = _roll(moves[name], p, q, setting.mechanics.rolling, setting.radius)
        assert abs(rolls - searched) <= 0.1 * abs(rolls) + 1e-4, (k, name, rolls, searched)
        if k == 0 or name != found.faces[k - 1] or marks[k] != marks[k - 1]:
            runs.append(([], hi - lo))
        runs[-1][0].append(rolls)
    return runs


def _contacts(rolls: list[float], width: float) -> int:
    """The contacts one after another that carry steps rolling ``rolls`` [m] on ``width`` [m] of face."""
    travel = np.concatenate([[0.0], np.cumsum(rolls)])
    contacts, first = 1, 0
    for j in range(1, len(travel)):
        if np.ptp(travel[first:j + 1]) > width:
            contacts, first = contacts + 1, j - 1
    return contacts


def test_the_search_counts_the_contact_rolling_as_the_inverse_push_model_does() -> None:
    """The search keeps track of how far each step rolls the contact along its face (a sideways step
    moves it 1/c^2 times as far, a turn of the heading R per radian) and starts a new contact where one
    cannot carry the run. Each step's rolling agrees with the project's inverse push model pushing the
    object along that step (the contact starting at the middle of the usable range; the search takes
    the heading there), and no run needs more than ``oe.max_contacts`` contacts by the model's rolling."""
    task = _task("exec60-00023")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task)
    found = guided_path(setting, np.array(task.start), np.array(task.target), options=options)
    assert isinstance(found, GuidedPath)
    for rolls, width in _rolling_by_run(found, setting, options):
        assert _contacts(rolls, width) <= options.max_contacts


@pytest.mark.parametrize("task_id", ["verd200-00001", "verd200-00065"])
def test_a_face_that_cannot_carry_a_run_in_its_contacts_pushes_in_shorter_steps_and_more_runs(task_id) -> None:
    """A short face pushing sideways rolls its contact off the face within one 4 mm step: the search takes
    half a step there (verd200-00001, the slope's 5 mm face); a run that needs more than
    ``oe.max_contacts`` contacts stops, and the face touches the resting object again for a new run
    (verd200-00065, the finger). Without these (``more=False``, the first attempts) its space closes.
    Each run needs at most ``oe.max_contacts`` contacts by the model's rolling, no step rolls more than
    the face's usable width, and the path fitted run by run is a solved push plan."""
    task = _verdict_task(task_id)
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8})
    plain = guided_path(setting, np.array(task.start), np.array(task.target), options=options)
    assert isinstance(plain, GuidedMiss) and plain.exhausted
    found = guided_path(setting, np.array(task.start), np.array(task.target), options=options, more=True)
    assert isinstance(found, GuidedPath), found
    steps = np.hypot(*np.diff(found.xy, axis=0).T)[:-1]
    assert np.any(steps < 0.003) or max(found.runs) > 0  # what the search could not do before
    runs = _rolling_by_run(found, setting, options)
    for rolls, width in runs:
        assert max(abs(r) for r in rolls) <= width + 1e-4
        assert _contacts(rolls, width) <= options.max_contacts
    tg = found.sequence(10.0)[0]
    plan = fit_runs(found.xy, found.faces, tg, setting, options, found.windows, found.runs)
    assert plan.status == "solved", plan.reason
    assert plan.metrics["piecewise_fits"] >= len(runs)
    assert np.linalg.norm(plan.object_xy[-1] - task.target) <= 1e-4


def test_a_search_that_cannot_move_says_its_space_closed() -> None:
    """A start no face can push from: the search's space closes at once, and it says so (not 'budget')."""
    task = _task("exec60-00023")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    far = np.array([5.0, 5.0])  # far outside the Omni's reach: no face holds the puck there
    miss = guided_path(setting, far, np.array(task.target), options=qp_options(task))
    assert isinstance(miss, GuidedMiss) and miss.exhausted and miss.expansions == 1
    assert "closed" in miss.describe()
    spent = guided_path(setting, np.array(task.start), np.array(task.target), options=qp_options(task), budget=5)
    assert isinstance(spent, GuidedMiss) and not spent.exhausted and spent.expansions == 5
    assert "budget" in spent.describe()


def test_a_guided_path_fitted_run_by_run_is_continuous_at_rest_between_runs_and_keeps_the_rules() -> None:
    """The fallback fit of a guided path (one fit per run of a face): one continuous path on one time
    axis from the start to the target, the object at rest wherever the face changes, every push's
    samples its own, and the object-path checks of a solved plan hold on the joined path."""
    task = _task("exec60-00023")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task)
    found = guided_path(setting, np.array(task.start), np.array(task.target), options=options)
    assert isinstance(found, GuidedPath)
    plan = fit_runs(found.xy, found.faces, 2.0 + found.sequence(10.0)[0], setting, options)
    assert plan.status == "solved", plan.reason
    runs = 1 + sum(a != b for a, b in zip(found.faces, found.faces[1:], strict=False))
    assert plan.metrics["piecewise_fits"] >= runs
    assert plan.t[0] == pytest.approx(2.0) and plan.t[-1] == pytest.approx(12.0) and np.all(np.diff(plan.t) > 0)
    assert np.allclose(plan.object_xy[0], task.start, atol=1e-9)
    assert np.linalg.norm(plan.object_xy[-1] - task.target) <= 1e-4
    assert np.hypot(*np.diff(plan.object_xy, axis=0).T).max() < 1e-3  # no jump where the fits meet
    seen = np.concatenate([p.samples for p in plan.pushes])
    assert np.all(np.diff(seen) >= 0) and seen[0] == 0 and seen[-1] == plan.t.size - 1
    contacts = [1]  # per run of a face: at most oe.max_contacts, as one push of the one fit
    for before, after in zip(plan.pushes, plan.pushes[1:], strict=False):
        if after.face != before.face:  # a switch: the object stands still while the tool goes round it
            assert np.linalg.norm(plan.object_v[after.samples[0]]) < 1e-6
            contacts.append(0)
        contacts[-1] += 1
    assert len(contacts) == runs and max(contacts) <= options.max_contacts
    frames = {f: FaceFrame.build(setting, f, friction_cone_fraction=options.friction_cone_fraction)
              for f in setting.tool.face_names}
    measured = plan_metrics(plan, frames, np.array(task.target), setting)
    assert hard_check_failures(measured) == []


def _verdict_task(task_id: str) -> Task:
    batch = ROOT / "problems" / "batch" / "verdicts_200.yaml"
    data = next(g.data for g in generate_tasks(load_batch(batch), batch) if g.task_id == task_id)
    return task_from_dict(data, str(batch))


def test_contact_windows_cover_each_face_evenly_and_the_middle_one_is_the_usable_range() -> None:
    from tooltransfer.planner.planning.oe.guided_moves import MAX_WINDOWS, contact_windows
    from tooltransfer.tools.pushing.inverse import FaceGeometry

    for task in (_task("exec60-00023"), _verdict_task("verd200-00056")):
        setting = setting_from_task(task, task_skills(task, need_ss=False))
        options = qp_options(task).model_copy(update={"contact_span": 0.004})
        for face in setting.tool.face_names:
            g = FaceGeometry.of(setting.tool, face)
            lo, hi = g.lo + options.contact_margin, g.hi - options.contact_margin
            wins = contact_windows(setting.tool, face, options)
            assert len(wins) % 2 == 1 and len(wins) <= MAX_WINDOWS
            assert wins[len(wins) // 2] == pytest.approx(usable_range(setting.tool, face, options))
            if hi - lo > options.contact_span:  # spread from one end of the face to the other, one span each
                assert wins[0][0] == pytest.approx(lo) and wins[-1][1] == pytest.approx(hi)
                assert all(b - a == pytest.approx(options.contact_span) for a, b in wins)
                gaps = np.diff([a for a, _ in wins])
                assert np.allclose(gaps, gaps[0]) and gaps[0] > 0  # evenly spaced
                if (hi - lo) / options.contact_span <= MAX_WINDOWS - 1:  # few enough: they cover the face
                    assert gaps[0] <= options.contact_span + 1e-12


def test_a_start_held_only_toward_one_end_of_a_face_is_pushed_from_with_the_contact_kept_there() -> None:
    """The slope's inclined face holds the puck at this start only with its contact on the upper part of
    the face: the search with the contact anywhere on the usable range (the fit holds the Omni at both
    of its ends) cannot move at all, the search by contact windows can. Each step it takes keeps the
    rules at both ends of its window (the Omni's inverse kinematics reaching the tool there)."""
    task = _verdict_task("verd200-00056")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8, "contact_span": 0.004})
    start, target = np.array(task.start), np.array(task.target)
    whole = guided_path(setting, start, target, options=options)
    assert isinstance(whole, GuidedMiss) and whole.exhausted and whole.expansions == 1
    found = guided_path(setting, start, target, options=options, windows=True, more=True)
    assert isinstance(found, GuidedPath), found
    assert len(found.windows) == len(found.faces)
    for k, (name, window) in enumerate(zip(found.faces, found.windows, strict=True)):
        lo, hi = window or usable_range(setting.tool, name, options)
        assert hi - lo <= options.contact_span + 1e-12
        assert all(_held_at(setting, name, s, found.xy[k], 0.8)[0] for s in (lo, hi))


def _widest(task: Task, share: float) -> Task:
    """``task`` with ``oe.friction_cone_fraction_max`` at ``share``."""
    return task.model_copy(update={"oe": task.oe.model_copy(update={"friction_cone_fraction_max": share})})


def test_the_contact_windows_are_tried_only_where_no_attempt_could_push_from_the_start() -> None:
    """The windows' attempt is the costliest (up to five moves per face): it runs where every attempt
    before it closed at the start (verd200-00056: no face holds the puck there with its contact at the
    middle of the face) and not where they moved and failed later (verd200-00011, its widest share
    0.8). Where they closed at the start, the fine steps' attempt is left out (which faces hold the puck
    there does not depend on the step), and so are the widest share's whole faces; where they moved, it
    runs after them. The attempt on the whole faces and their windows where the whole is not held runs
    in both cases (on fine steps), at 0.8 of the cone and, last, at the widest share where that is wider;
    after them all, in both cases, the attempts in the distance field's order, on whole faces and their windows
    where needed, then on every face's windows (tests/test_guided_field.py), and where a search on whole steps
    ended on its budget (verd200-00011's do), the weighted search made again (tests/test_guided_spent.py), and
    last the attempt on narrow windows (tests/test_guided_narrow.py), then the closest attempt's
    (tests/test_guided_close.py). verd200-00056 is solved by the windows' attempt."""
    from guided_ladder import ladder_plans

    # three attempts closed at once; the windows' gives a push plan (its approach, at the edge of the
    # Omni's workspace, comes in along the face: assemble.WIDE_TURNS), and the whole plan passes; the two
    # on whole faces and windows where not held miss; the seventh and eighth, the field's, give push plans too;
    # the ninth is on narrow windows, the tenth the closest attempt's
    plans = ladder_plans(_verdict_task("verd200-00056"))
    ladder = [p.reason or "" for p in plans]
    assert len(ladder) == 10 and all("its space closed after 1 expansions" in a for a in ladder[:3])
    assert all(" 2 mm steps" not in a and " 2 mm, " not in a for a in ladder[:4])
    assert plans[3].status == "solved" and plans[3].metrics["guided_step"] == pytest.approx(0.004)
    for a, share in zip(ladder[4:6], ("0.8", "0.95"), strict=True):
        assert a.startswith(f"at {share} of the friction cone") and "where that is not held, on its 4 mm windows" in a
    assert all(p.status == "solved" and p.metrics["guided_field"] == 1.0 for p in plans[6:8])
    assert plans[8].metrics.get("guided_narrow") == 1.0 or "on its 2 mm windows" in ladder[8]
    assert plans[9].metrics.get("guided_close") == 1.0 or "each step ending where its face holds" in ladder[9]
    stuck = solve(_verdict_task("verd200-00056"))
    assert stuck.verdict == "solved" and "guided_field" not in stuck.metrics
    assert stuck.metrics["alternatives_tried"] == 4
    moved = solve(_widest(_verdict_task("verd200-00011"), 0.8))
    assert moved.verdict != "solved"
    attempts = (moved.reason or "").split("the guided search: ")[1].split("; then ")
    assert not any("windows of each face" in a for a in attempts[:5])
    assert "half steps and new runs" in attempts[2] and " 4 mm steps" in attempts[2]
    assert "no path within 4000 expansions of 4 mm steps" in attempts[2]  # on its budget
    assert " 2 mm steps" in attempts[3] and "windows" not in attempts[3]
    assert "where that is not held, on its 4 mm windows" in attempts[4] and " 2 mm steps" in attempts[4]
    assert "where that is not held, on its 4 mm windows" in attempts[5] and "over a grid of where" in attempts[5]
    assert "4 mm windows of each face" in attempts[6] and "over a grid of where the faces push" in attempts[6]
    assert "again after a search on whole steps spent its budget" in attempts[7] and " 4 mm steps" in attempts[7]
    assert "weighted 3" in attempts[7] and "windows" not in attempts[7]
    assert "where that is not held, on its 2 mm windows" in attempts[8]
    assert "where that is not held, on its 1 mm windows" in attempts[9] and "each step ending where" in attempts[9]
    assert len(attempts) == 10


def test_a_passage_whole_steps_miss_is_found_on_fine_steps_and_the_plan_executes() -> None:
    """exec60-00040 (finger, one obstacle): on 4 mm steps the search's space closes at both shares of
    the friction cone; on 2 mm steps and 1 mm cells it finds a path, and the plan made from it passes
    every hard check (the tool 0.25 mm or more from the obstacle among them) and ends within 5 mm of the
    target open loop on the MuJoCo platform."""
    pytest.importorskip("mujoco")
    from tooltransfer.planner.execution.simulate import simulate_plan
    from tooltransfer.planner.planning.oe.guided import CELL, FINE, STEP

    task = _task("exec60-00040")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    start, target = np.array(task.start), np.array(task.target)
    for share in (0.5, 0.8):
        options = qp_options(task).model_copy(update={"friction_cone_fraction": share})
        miss = guided_path(setting, start, target, options=options, budget=4000, more=share > 0.5)
        assert isinstance(miss, GuidedMiss) and miss.exhausted
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8})
    found = guided_path(setting, start, target, options=options, budget=8000, more=True, step=FINE * STEP,
                        cell=FINE * CELL)
    assert isinstance(found, GuidedPath)
    plan = solve(task)
    assert plan.verdict == "solved" and plan.metrics["guided_step"] == pytest.approx(FINE * STEP)
    assert hard_check_failures(plan.metrics) == []
    assert plan.metrics["tool_obstacle_clearance_min"] >= 0.00025
    assert simulate_plan(plan).final_error < 0.005


def test_a_tool_closer_to_an_obstacle_than_the_safety_envelope_allows_breaks_a_hard_check() -> None:
    """The closed loop's envelope refuses commands within 0.25 mm of an obstacle: a plan passing closer
    is not solved (its tool or a switch), one at the margin is."""
    from tooltransfer.planner.execution.envelope import ENVELOPE_MARGIN
    from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN

    assert TOOL_MARGIN == ENVELOPE_MARGIN == 0.00025
    for key, family in (("tool_obstacle_clearance_min", "tool-obstacle clearance"),
                        ("switch_obstacle_clearance_min", "switch-obstacle clearance")):
        close = hard_check_failures({key: 0.0001})
        assert len(close) == 1 and close[0].startswith(family)
        assert hard_check_failures({key: TOOL_MARGIN}) == []


def test_the_last_attempt_uses_a_face_s_windows_only_where_the_whole_face_is_not_held() -> None:
    """verd200-00129 (l_shape, two obstacles): on fine steps at 0.8 of the friction cone, weighted toward
    the target and with the last attempt's room, the search with the contact on the whole usable range of
    each face finds no path within the last attempt's expansions; with each face's 4 mm windows where the
    whole face is not held (``mixed``) it does, with steps of both kinds. Every step keeps the rules at both
    ends of its window or of the whole range (the Omni's inverse kinematics reaching the tool there, the
    outline the last attempt's room clear of the obstacles), and a window starts only where its face is not
    held as a whole under the search's rule: the windows add moves where the whole face has none."""
    from tooltransfer.planner.planning.oe.guided import CELL, FINE, STEP
    from tooltransfer.planner.planning.oe.guided_holds import _Holds, _zones
    from tooltransfer.planner.planning.oe.guided_moves import _face_moves
    from tooltransfer.planner.planning.oe.guided_rungs import GREED, LAST_ROOM

    task = _verdict_task("verd200-00129")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8})
    start, target = np.array(task.start), np.array(task.target)
    fine = {"step": FINE * STEP, "cell": FINE * CELL, "budget": round(options.guided_budget / FINE), "more": True,
            "room": LAST_ROOM}
    assert isinstance(guided_path(setting, start, target, options=options, greed=GREED, **fine), GuidedMiss)
    found = guided_path(setting, start, target, options=options, greed=GREED, mixed=options.guided_contact_span,
                        **fine)
    assert isinstance(found, GuidedPath), found
    assert len(found.windows) == len(found.faces)
    assert any(w is not None for w in found.windows) and any(w is None for w in found.windows)
    whole_held = _Holds(_face_moves(setting, options), np.asarray(setting.tool.outline.exterior.coords),
                        _zones(setting, LAST_ROOM)[0])

    for k, (name, window) in enumerate(zip(found.faces, found.windows, strict=True)):
        whole = usable_range(setting.tool, name, options)
        lo, hi = window or whole
        assert hi - lo <= (options.guided_contact_span if window else options.contact_span) + 1e-12
        for s in (lo, hi):
            reached, body = _held_at(setting, name, s, found.xy[k], 0.8)
            assert reached and _room(setting, body) > LAST_ROOM
        if window is not None and (k == 0 or (found.faces[k - 1], found.windows[k - 1]) != (name, window)):
            assert name not in {key for key, *_ in whole_held(found.xy[k])}  # begun where the whole is not held


def test_a_task_only_the_last_attempt_solves_gets_a_plan_that_executes() -> None:
    """verd200-00099 (l_shape, no obstacle): the fine attempt (whole faces, 2 mm steps, 8000 expansions)
    finds no path within its expansions; the last attempt, weighted toward the target, does, and its plan
    passes every hard check and ends within 5 mm of the target open loop on the MuJoCo platform."""
    pytest.importorskip("mujoco")
    from tooltransfer.planner.execution.simulate import simulate_plan
    from tooltransfer.planner.planning.oe.guided import CELL, FINE, STEP

    task = _verdict_task("verd200-00099")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": 0.8})
    miss = guided_path(setting, np.array(task.start), np.array(task.target), options=options, more=True,
                       step=FINE * STEP, cell=FINE * CELL, budget=round(options.guided_budget / FINE))
    assert isinstance(miss, GuidedMiss)
    plan = solve(task)
    assert plan.verdict == "solved" and plan.metrics["guided_step"] == pytest.approx(FINE * STEP)
    assert plan.metrics["friction_cone_fraction"] == pytest.approx(0.8)
    assert hard_check_failures(plan.metrics) == []
    assert simulate_plan(plan).final_error < 0.005


def test_a_task_only_the_widest_share_of_the_cone_solves_gets_a_plan_at_that_share_last() -> None:
    """verd200-00011 (slope, no obstacle): with the widest share at 0.8 no attempt finds a plan (the
    ladder test above); at the default ``oe.friction_cone_fraction_max`` (0.95) the attempts at that share
    come after every attempt at 0.8 and one of them finds a plan, which records the share it used, passes
    every hard check (its cone measured at that share) and ends within 5 mm of the target open loop on
    the MuJoCo platform."""
    pytest.importorskip("mujoco")
    from tooltransfer.planner.execution.simulate import simulate_plan

    task = _verdict_task("verd200-00011")
    assert task.oe.friction_cone_fraction_max == pytest.approx(0.95)
    plan = solve(task)
    assert plan.verdict == "solved", plan.reason
    assert plan.metrics["friction_cone_fraction"] == pytest.approx(0.95) and plan.metrics["guided_widest"] == 1.0
    assert plan.metrics["alternatives_tried"] >= 6  # the scored candidates, then five attempts at 0.5 and 0.8
    assert hard_check_failures(plan.metrics) == []
    assert simulate_plan(plan).final_error < 0.005


def test_the_widest_share_is_tried_only_where_it_widens_some_face_s_cone() -> None:
    """On l_shape every face's push cone of the tool file (``push_angle +- theta_b``) lies inside 0.8 of the
    friction cone, so an attempt at 0.95 would search and fit the same cones again: exec60-00054 (l_shape;
    certified infeasible after the search, by the switches its tool cannot make) makes none; the slope's
    ``inclined`` face's cone does widen (verd200-00011 is solved at 0.95, the test above)."""
    from tooltransfer.planner.planning.oe.guided_rungs import _widens

    task = _task("exec60-00054")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    half = setting.mechanics.friction_angle
    for f in setting.tool.faces:  # the tool file's cone within 0.8 of the friction cone, either side
        off = math.remainder(f.push_angle - f.normal_angle, 2 * math.pi)
        assert abs(off) + f.theta_b <= 0.8 * half
    assert not _widens(setting, 0.8, 0.95)
    plan = solve(task)
    assert plan.verdict == "infeasible" and plan.evidence["kind"] == "switch_separated"
    assert "at 0.95 of the friction cone" not in (plan.reason or "")
    assert "at 0.8 of the friction cone" in (plan.reason or "")
    slope = _verdict_task("verd200-00011")
    assert _widens(setting_from_task(slope, task_skills(slope, need_ss=False)), 0.8, 0.95)
