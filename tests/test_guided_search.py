"""The ``qp`` variant's guided search: where the scored candidates find no plan, a best-first search
over puck positions proposes a face sequence that the QP fit refines; the plan it gives passes every
hard check and executes on the MuJoCo platform."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tooltransfer.planner.apps.batch.generate import generate_tasks
from tooltransfer.planner.apps.batch.spec import load_batch
from tooltransfer.planner.planning.oe.guided import guided_path
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import hard_check_failures, solve
from tooltransfer.problems.task import Task, task_from_dict

ROOT = Path(__file__).resolve().parents[1]
BATCH = ROOT / "problems" / "batch" / "execution_60.yaml"


def _task(task_id: str) -> Task:
    data = next(g.data for g in generate_tasks(load_batch(BATCH), BATCH) if g.task_id == task_id)
    return task_from_dict(data, str(BATCH))


def test_the_guided_path_keeps_the_rules_it_searches_under() -> None:
    task = _task("exec60-00023")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    found = guided_path(setting, np.array(task.start), np.array(task.target), cone_fraction=0.5)
    assert found is not None
    assert np.allclose(found.xy[0], task.start) and np.allclose(found.xy[-1], task.target)
    assert len(found.faces) == len(found.xy) - 1 and set(found.faces) <= set(setting.tool.face_names)
    steps = np.hypot(*np.diff(found.xy, axis=0).T)
    assert steps.max() <= 0.004 + 1e-9
    t, ref, faces, switches = found.sequence(10.0)
    assert ref is found.xy
    assert t[0] == 0.0 and t[-1] == pytest.approx(10.0) and len(switches) == len(faces) - 1
    assert all(0.0 < a < b for a, b in zip(switches, [*switches[1:], 10.0], strict=True))


def test_a_task_the_candidates_miss_is_solved_by_the_guided_search_and_executes() -> None:
    pytest.importorskip("mujoco")
    from tooltransfer.planner.execution.simulate import simulate_plan

    plan = solve(_task("exec60-00023"))
    assert plan.verdict == "solved" and "time_guided" in plan.metrics
    assert hard_check_failures(plan.metrics) == []
    assert plan.metrics["self_consistency_max"] <= 1e-4
    assert simulate_plan(plan).final_error < 0.005
