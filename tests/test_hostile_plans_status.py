"""Plans called solved but are not (issue 16, class 7): a whole plan that breaks a hard check is
``violated``, with the families it breaks in its reason; it is still written (and read back), compared
and counted apart (``compare``, batch reports); ``solve`` exits 1 for it; the reviewer's case whose
only face pushes away is not solved with the paper's mapping variant either."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tooltransfer.planner.planning.solve as solve_module
from tooltransfer.planner.apps.batch.report import print_report, summarize, top_reasons
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.planning.plan import read_plan
from tooltransfer.planner.planning.solve import HARD_CHECKS, hard_check_failures

ROOT = Path(__file__).resolve().parents[1]
TRANSFER = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
AWAY = ROOT / "problems" / "hard" / "only_face_pushes_away.yaml"

GOOD = {"cone_violation_max": 5e-4, "friction_cone_margin_min": 0.3, "contact_edge_margin_min": 2e-4,
        "switch_penetration_max": 1e-7, "reach_violation_max": 0.0, "tool_obstacle_clearance_min": 0.005,
        "switch_obstacle_clearance_min": 0.005, "joint_limit_violation_max": 0.0, "goal_error": 1e-12,
        "self_consistency_max": 1e-5, "obstacle_clearance_min": 0.006, "safety_margin_used": 0.005}


def test_a_plan_within_every_hard_check_has_no_failure() -> None:
    assert hard_check_failures(GOOD) == []
    assert hard_check_failures({}) == []  # nothing measured, nothing broken
    assert hard_check_failures({**GOOD, "friction_cone_margin_min": float("nan")}) == []  # no pushes


@settings(derandomize=True, database=None, max_examples=60, deadline=None)
@given(i=st.integers(0, len(HARD_CHECKS) - 1), excess=st.floats(1e-3, 1e3))
def test_each_family_broken_is_named_with_its_metric(i: int, excess: float) -> None:
    family, key, bound, sense, _ = HARD_CHECKS[i]
    value = bound + excess if sense == "max" else bound - excess
    broken = hard_check_failures({**GOOD, key: value})
    assert len(broken) == 1 and broken[0].startswith(f"{family} ({key} ")


def test_the_safety_margin_and_self_consistency_are_hard_checks() -> None:
    assert hard_check_failures({**GOOD, "obstacle_clearance_min": 0.004})[0].startswith("safety margin")
    assert hard_check_failures({**GOOD, "self_consistency_max": 0.01}, 1e-4)[0].startswith("self-consistency")


def test_the_mapping_variant_on_the_face_that_pushes_away_is_not_solved(capsys) -> None:
    assert main(["solve", str(AWAY), "--oe", "mapping", "--ss", "opt", "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["status"] in ("infeasible", "violated") and out["reason"]


@pytest.fixture
def strict(monkeypatch: pytest.MonkeyPatch) -> None:
    """Hard checks strict enough that the transfer's qp plan breaks the cone check (it keeps 6e-4 rad)."""
    checks = tuple((f, k, -1.0 if k == "cone_violation_max" else b, s, u) for f, k, b, s, u in HARD_CHECKS)
    monkeypatch.setattr(solve_module, "HARD_CHECKS", checks)


def test_a_violated_plan_is_written_whole_read_back_and_exits_3(strict, tmp_path: Path, capsys) -> None:
    """A plan that breaks a hard check is no verdict: ``unknown`` (exit 3), the plan kept whole."""
    out = tmp_path / "plan.json"
    assert main(["solve", str(TRANSFER), "--variant", "qp/opt", "-o", str(out), "--json"]) == 3
    summary = json.loads(capsys.readouterr().out)
    assert summary["status"] == "unknown" and summary["violated"] is True
    assert summary["reason"].startswith("hard checks violated: cone (")
    plan = read_plan(out)
    assert plan.status == "violated" and "cone_violation_max" in plan.reason
    assert plan.t.size > 100 and plan.joints.shape == (plan.t.size, 3) and plan.pushes  # the whole plan
    assert main(["simulate", str(out)]) == 1  # not run unless forced
    assert "--force" in capsys.readouterr().out


def test_compare_counts_violated_plans_apart(strict, tmp_path: Path, capsys) -> None:
    assert main(["compare", str(TRANSFER), "--out", str(tmp_path)]) == 1
    text = capsys.readouterr().out
    assert "violated" in text and "plans: solved 0, violated" in text
    assert "qp/opt violated: cone" in text.replace("\n", " ")
    assert read_plan(tmp_path / "plan_transfer_tool2_qp_opt.json").status == "violated"


def test_batch_reports_count_violated_rows_apart(capsys) -> None:
    from rich.console import Console

    rows = []
    for i in range(10):
        status = "solved" if i < 4 else "violated" if i < 7 else "infeasible"
        rows.append({"task_id": f"t-{i}", "variant": "mapping/arch", "tool": "slope", "status": status,
                     "reason": "hard checks violated: cone (cone_violation_max 2 rad > 0.01)" if status == "violated"
                     else ("reach" if status == "infeasible" else ""), "time_total": 0.1,
                     "cone_violation_max": 0.001 if status == "solved" else 2.0})
    stats = {(s.tool, s.variant): s for s in summarize(rows)}
    s = stats[("slope", "mapping/arch")]
    assert (s.solved, s.violated, s.infeasible, s.n) == (4, 3, 3, 10)
    assert math.isclose(s.rate, 0.4) and s.valid == 4 and s.cone_violation_max == 0.001  # violated: not solved
    reasons = top_reasons(rows)
    assert any(r["status"] == "violated" and r["count"] == 3 and "cone" in r["reason"] for r in reasons)
    console = Console(width=220, record=True, color_system=None)
    print_report(list(stats.values()), reasons, console)
    assert "violated" in console.export_text()
