"""A test helper: the guided search's ladder of attempts for a task, driven as
:func:`tooltransfer.planner.planning.solve._guided` drives it, with what each attempt reports; and a task's
plan from one of its last attempts, checked as every such test checks it."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.planner.planning.oe.generalize import generalize
from tooltransfer.planner.planning.oe.guided import guided_plans
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import hard_check_failures, qp_options, solve
from tooltransfer.problems.task import Task


def ladder_reasons(task: Task, keep_after_first: bool = False) -> list[str]:
    """The reason of each attempt of ``task``'s ladder, in order ("" for a push plan the search and its fit
    solved), sending back after the first either nothing or a whole plan kept (with little room)."""
    return [p.reason or "" for p in ladder_plans(task, keep_after_first)]


def ladder_plans(task: Task, keep_after_first: bool = False) -> list[PushPlan]:
    """The push plan of each attempt of ``task``'s ladder, in order (as :func:`ladder_reasons`)."""
    skills = task_skills(task, need_ss=False)
    setting = setting_from_task(task, skills)
    start, target = np.array(task.start), np.array(task.target)
    t, x, _ = generalize(skills.oe.dmp, start, target)
    ladder = guided_plans(t, x, setting, target, qp_options(task))
    plans: list[PushPlan] = []
    sent = None
    while True:
        try:
            plan = ladder.send(sent)
        except StopIteration:
            return plans
        plans.append(plan)
        kept = Plan(status="solved", variant={}, task={}, platform={}, object={}, tool={}, obstacles=[])
        sent = kept if keep_after_first and len(plans) == 1 else None


def executed_plan_of(task: Task, attempt: str) -> Plan:
    """``task``'s plan, solved, from the ladder's attempt whose metric ``attempt`` (``guided_field``,
    ``guided_spent``) it carries, at 0.8 of the friction cone, passing every hard check and ending within
    5 mm of the target open loop on the MuJoCo platform (skipped without MuJoCo)."""
    pytest.importorskip("mujoco")
    from tooltransfer.planner.execution.simulate import simulate_plan

    plan = solve(task)
    assert plan.verdict == "solved", plan.reason
    assert plan.metrics[attempt] == 1.0 and plan.metrics["friction_cone_fraction"] == pytest.approx(0.8)
    assert hard_check_failures(plan.metrics) == []
    assert simulate_plan(plan).final_error < 0.005
    return plan
