"""A test helper: the guided search's ladder of attempts for a task, driven as
:func:`tooltransfer.planner.planning.solve._guided` drives it, with what each attempt reports."""

from __future__ import annotations

import numpy as np

from tooltransfer.planner.planning.oe.generalize import generalize
from tooltransfer.planner.planning.oe.guided import guided_plans
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import qp_options
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
