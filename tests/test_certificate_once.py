"""A certificate is a property of the task, not of the variant (issue 26): the looks for one are made once per
task in a process (verdicts/decide.py, ``remembered``), so ``compare``'s variants share them; a look is taken
again only where what it depends on is the same (the world, start, target and budget)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import solve
from tooltransfer.planner.planning.verdicts import decide
from tooltransfer.problems.task import Variants, load_task

ROOT = Path(__file__).resolve().parents[1]
OUT_OF_REACH = ROOT / "problems" / "hard" / "target_out_of_reach.yaml"


def test_a_look_is_made_once_per_task_and_budget() -> None:
    task = load_task(OUT_OF_REACH)
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    start, target = np.array(task.start), np.array(task.target)
    decide._LOOKS.clear()
    first = decide.seek_certificate(setting, start, target)
    again = decide.seek_certificate(setting, start.copy(), target.copy())
    assert first.cert is not None and not first.reused
    assert again.reused and again.why == first.why and again.shared == first.spent
    assert again.cert is not None and again.cert is not first.cert  # each plan its own copy
    assert again.cert.to_dict() == first.cert.to_dict()
    assert not decide.seek_certificate(setting, start, target, budget=2.0).reused  # another budget
    assert not decide.seek_certificate(setting, start + 1e-6, target).reused  # another start
    assert not decide.seek_certificate(replace(setting, margin=setting.margin + 1e-3), start, target).reused
    # a setting made again from the task is the same world
    same = setting_from_task(task, task_skills(task, need_ss=False))
    assert same is not setting and decide.seek_certificate(same, start, target).reused


def test_the_second_variant_of_a_task_reuses_the_first_ones_certificate() -> None:
    task = load_task(OUT_OF_REACH)
    decide._LOOKS.clear()
    qp = solve(task, OUT_OF_REACH)
    mapping = solve(task.model_copy(update={"variants": Variants(oe="mapping", ss="opt")}), OUT_OF_REACH)
    assert qp.status == mapping.status == "infeasible"
    assert qp.evidence is not None and mapping.evidence is not None
    assert "certificate_reused" not in qp.evidence and mapping.evidence["certificate_reused"] is True
    assert mapping.evidence["time_certify_shared"] > 0.0  # the first look's time, kept
    assert mapping.evidence["certificate"] == qp.evidence["certificate"]
