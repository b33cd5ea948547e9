"""An ``unknown`` verdict says whether its search or its certificate stopped on a budget (a larger
``--budget`` may then decide the task) or ended within its budgets (every attempt of the guided search
closed its space under its own rules, every grid's set reached the start: a larger budget is unlikely to
help). The two generated tasks are of the verdict benchmark, one of each kind."""

from __future__ import annotations

import json
import re

import numpy as np
from test_verdicts import ROOT, _rules_of, generated

from tooltransfer.planner.apps.batch.generate import generate_tasks
from tooltransfer.planner.apps.batch.html_report import summary_table
from tooltransfer.planner.apps.batch.report import summarize
from tooltransfer.planner.apps.batch.spec import load_batch
from tooltransfer.planner.apps.batch.store import ResultStore
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.planning.plan import read_plan
from tooltransfer.planner.planning.solve import solve
from tooltransfer.planner.planning.verdicts.certificate import certify
from tooltransfer.planner.planning.verdicts.decide import budget_limited


def test_budget_limited_reads_the_guided_attempts_and_the_certificates_block_budget() -> None:
    closed = "backward-reachable set of the target: cells of 10 mm: the set came within the gap of the start"
    assert not budget_limited({"guided_attempts": 4.0, "guided_attempts_on_budget": 0.0}, closed)
    assert budget_limited({"guided_attempts": 4.0, "guided_attempts_on_budget": 1.0}, closed)
    assert budget_limited({}, "backward-reachable set of the target: cells of 10 mm: budget: 20000 block updates")
    assert not budget_limited({}, "")


def test_a_certificate_out_of_block_updates_makes_the_verdict_budget_limited() -> None:
    """The certificate's own words when its set runs out of block updates are what the flag reads."""
    task = generated("execution_60.yaml", "exec60-00015")
    _, rules = _rules_of(task)
    cert, why = certify(rules, np.array(task.start), np.array(task.target), max_blocks=3)
    assert cert is None and "budget" in why
    assert budget_limited({}, why)


def test_an_unknown_whose_searches_closed_their_space_is_not_budget_limited() -> None:
    """verd200-00049 (one obstacle): every attempt expands every lattice cell it can reach, and every
    certificate's set reaches the start or the target within its budget."""
    task = generated("verdicts_200.yaml", "verd200-00049")
    plan = solve(task)
    assert plan.status == "unknown", plan.reason
    assert plan.metrics["guided_attempts"] >= 4 and plan.metrics["guided_attempts_on_budget"] == 0
    assert plan.evidence["budget_limited"] is False
    assert "its space closed" in plan.reason and "its budget" not in plan.reason


def test_an_unknown_whose_search_ran_out_of_expansions_is_budget_limited() -> None:
    """verd200-00120 (finger, one obstacle) with the search's least budget (``oe.guided_budget`` 100; with the
    default 4000 the ladder's closest attempt solves it): attempts on fine steps spend their expansions."""
    task = generated("verdicts_200.yaml", "verd200-00120")
    task = task.model_copy(update={"oe": task.oe.model_copy(update={"guided_budget": 100})})
    plan = solve(task)
    assert plan.status == "unknown", plan.reason
    assert plan.metrics["guided_attempts_on_budget"] >= 1
    assert plan.evidence["budget_limited"] is True
    assert "(its budget, oe.guided_budget)" in plan.reason


def test_the_batch_report_counts_the_unknowns_that_stopped_on_a_budget(tmp_path) -> None:
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.add_tasks([{"task_id": f"t{i}", "idx": i, "tool": "slope", "n_obstacles": 0} for i in range(4)])
        for i, spent in enumerate((True, False, True)):
            store.put({"task_id": f"t{i}", "variant": "qp/opt", "tool": "slope", "status": "unknown",
                       "metrics_json": json.dumps({"evidence": {"verdict": "unknown", "budget_limited": spent}})})
        store.put({"task_id": "t3", "variant": "qp/opt", "tool": "slope", "status": "solved"})
        rows = store.rows()
    stats = summarize(rows)
    s = {(g.tool, g.variant): g for g in stats}[("slope", "qp/opt")]
    assert (s.unknown, s.unknown_on_budget, s.solved) == (3, 2, 1)
    page = summary_table(stats)  # the report page's summary: the count in its own column
    head = re.findall(r"<th[^>]*>([^<]*)</th>", page)
    first = re.search(r"<tbody><tr>(.*?)</tr>", page)
    assert first is not None
    cells = re.findall(r"<td[^>]*>([^<]*)</td>", first.group(1))
    assert cells[head.index("unknown on a budget")] == "2" and cells[head.index("unknown")] == "3"


def test_solve_json_says_whether_an_unknown_stopped_on_a_budget(tmp_path, capsys) -> None:
    """The command line's summary of an unknown carries the flag (exit code 3: unknown)."""
    batch = ROOT / "problems" / "batch" / "verdicts_200.yaml"
    data = next(g.data for g in generate_tasks(load_batch(batch), batch) if g.task_id == "verd200-00049")
    path = tmp_path / "verd200-00049.yaml"
    path.write_text(json.dumps(data))  # JSON is YAML; the generated task's paths are absolute
    assert main(["solve", str(path), "--json", "-o", str(tmp_path / "plan.json")]) == 3
    summary = json.loads(capsys.readouterr().out)
    assert summary["status"] == "unknown" and summary["evidence"] == "search_exhausted"
    assert summary["budget_limited"] is False
    # its start is held only on the last millimetre of one face (tests/test_holds_at.py): the reason says so
    assert "at the start the contact holds the puck only on 1 mm of 'foot_end'" in summary["reason"]
    holds = read_plan(tmp_path / "plan.json").evidence["holds"]  # and the plan file keeps where, face by face
    assert [h["face"] for h in holds["start"] if h["windows"]] == ["foot_end"] and len(holds["target"]) == 4


def test_a_task_the_certificate_proves_infeasible_is_not_searched_further() -> None:
    """The certificate is looked for before the guided search (a sound one leaves it nothing to find):
    exec60-00016 (certified) runs no attempt of it, and its time to certify is part of its planning time;
    verd200-00049 (unknown) runs the guided search after the certificate failed, and keeps that look's
    account and time."""
    certified = solve(generated("execution_60.yaml", "exec60-00016"))
    assert certified.status == "infeasible" and certified.evidence["kind"] == "backward_reachable"
    assert "guided_attempts" not in certified.metrics and "the guided search" not in certified.reason
    assert certified.metrics["time_certify"] > 0
    unknown = solve(generated("verdicts_200.yaml", "verd200-00049"))
    assert unknown.status == "unknown" and unknown.metrics["guided_attempts"] >= 4
    assert unknown.evidence["not_proved"].startswith("backward-reachable set of the target")
    assert unknown.metrics["time_certify"] > 0


def test_the_planning_time_counts_the_certificate_and_the_guided_search_once() -> None:
    """A certified task's planning time holds its look for the certificate (and no guided search); an
    unknown's holds both the look and the guided search's attempts (verd200-00049 closes its attempts'
    spaces quickly)."""
    certified = solve(generated("execution_60.yaml", "exec60-00016"))
    m = certified.metrics
    assert "time_guided" not in m and certified.planning_time >= m["time_certify"]
    unknown = solve(generated("verdicts_200.yaml", "verd200-00049"))
    m = unknown.metrics
    assert unknown.planning_time >= m["time_certify"] + m["time_guided"]
    assert unknown.planning_time <= m["time_certify"] + m["time_guided"] + m["time_skills"] + m["time_oe"] + 1.0
