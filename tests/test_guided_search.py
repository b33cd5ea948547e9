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
        face = setting.tool.face(name)
        lo, hi = usable_range(setting.tool, name, options)
        for s in (lo, hi):
            frame = FaceFrame.build(setting, name, s=s / face.length,
                                    friction_cone_fraction=options.friction_cone_fraction)
            x, y, yaw = frame.tool_pose(p[None])[0]
            ik = inverse_kinematics(setting.platform, [x, y])
            assert ik.reachable and ik.heading is not None
            assert abs(math.remainder(ik.heading - yaw, 2 * math.pi)) < 1e-6
            rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
            body = shapely.Polygon(np.asarray(setting.tool.outline.exterior.coords) @ rot.T + [x, y])
            assert all(shapely.distance(body, o.polygon() if isinstance(o, Disc) else o) > 0.0
                       for o in setting.obstacles)
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
    from tooltransfer.planner.planning.oe.guided import CONE, _face_moves, _pointing, _stepped

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


def test_the_search_counts_the_contact_rolling_as_the_inverse_push_model_does() -> None:
    """The search keeps track of how far each step rolls the contact along its face (a sideways step
    moves it 1/c^2 times as far, a turn of the heading R per radian) and starts a new contact where one
    cannot carry the run. Each step's rolling agrees with the project's inverse push model pushing the
    object along that step (the contact starting at the middle of the usable range; the search takes
    the heading there), and no run needs more than ``oe.max_contacts`` contacts by the model's rolling."""
    from tooltransfer.planner.planning.oe.guided import _face_moves, _roll
    from tooltransfer.tools.pushing.inverse import push_tool_path

    task = _task("exec60-00023")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task)
    found = guided_path(setting, np.array(task.start), np.array(task.target), options=options)
    assert isinstance(found, GuidedPath)
    moves = {fm.name: fm for fm in _face_moves(setting, options)}
    runs: dict[int, list[float]] = {}
    run = 0
    for k, name in enumerate(found.faces):
        run += int(k > 0 and name != found.faces[k - 1])
        lo, hi = usable_range(setting.tool, name, options)
        p, q = found.xy[k], found.xy[k + 1]
        model = push_tool_path(setting.tool, name, np.linspace(p, q, 9), setting.radius, setting.mechanics,
                               0.5 * (lo + hi), platform=setting.platform)
        rolls = float(model.s[-1] - model.s[0])
        searched = _roll(moves[name], p, q, setting.mechanics.rolling, setting.radius)
        assert abs(rolls - searched) <= 0.1 * abs(rolls) + 1e-4, (k, name, rolls, searched)
        runs.setdefault(run, []).append(rolls)
        runs[run].append(hi - lo)
    for steps in runs.values():  # the contacts each run needs by the model's rolling, one after another
        travel, width = np.concatenate([[0.0], np.cumsum(steps[0::2])]), steps[1]
        contacts, first = 1, 0
        for j in range(1, len(travel)):
            if np.ptp(travel[first:j + 1]) > width:
                contacts, first = contacts + 1, j - 1
        assert contacts <= options.max_contacts


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
