"""Every plan metric has its unit in one table (tooltransfer.planner.common.metric_units), which the command
line's summary, the plan file, the batch store's report and the paper's report use instead of
guessing from the name."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from rich.console import Console

from tooltransfer.planner.apps.batch.execute import METRIC_COLUMNS
from tooltransfer.planner.apps.batch.report import print_report, summarize, top_reasons
from tooltransfer.planner.apps.batch.store import RESULT_COLUMNS, TASK_COLUMNS
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.apps.paper_run import ROWS
from tooltransfer.planner.common.metric_units import COLUMN_UNITS, UNITS, column_unit, display, label, shown, unit
from tooltransfer.planner.planning.plan import read_plan
from tooltransfer.planner.planning.solve import HARD_CHECKS

TRANSFER = Path(__file__).resolve().parents[1] / "problems" / "paper" / "transfer_tool2.yaml"


def test_a_solved_plans_metrics_all_have_a_unit(tmp_path: Path, capsys) -> None:
    out = tmp_path / "plan.json"
    assert main(["solve", str(TRANSFER), "--variant", "mapping/arch", "-o", str(out), "--json"]) in (0, 1, 3)
    summary = json.loads(capsys.readouterr().out)
    metrics = json.loads(out.read_text())["metrics"]
    assert {k for k in metrics if not k.startswith("violation_")} <= set(UNITS)
    assert {k for k, v in summary.items() if isinstance(v, float)} <= set(UNITS)


def test_units_of_the_checks_and_the_batch_columns() -> None:
    assert all(u == UNITS[key] for _, key, _, _, u in HARD_CHECKS)
    assert set(METRIC_COLUMNS) <= set(UNITS)
    assert unit("goal_error") == "m" and unit("cone_violation_max") == "rad" and unit("duration") == "s"
    assert unit("n_pushes") == "" and unit("no_such_metric") is None
    assert shown("goal_error", 0.0012) == ("goal_error [mm]", "1.2")
    assert shown("open_loop_tracking_error", 0.01) == ("open_loop_tracking_error [rad]", "0.01")
    assert shown("closed_loop_replan_time_median", 0.019) == ("closed_loop_replan_time_median [s]", "0.019")
    assert shown("real_time_factor", 2.0) == ("real_time_factor", "2")


def test_a_solved_plan_file_carries_the_units_of_its_metrics(tmp_path: Path, capsys) -> None:
    out = tmp_path / "plan.json"
    assert main(["solve", str(TRANSFER), "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    doc = json.loads(out.read_text())
    assert doc["status"] == "solved"
    assert summary["planning_time"] == doc["metrics"]["time_total"]  # the solve once, not its stages on top
    metrics, units = doc["metrics"], doc["metric_units"]
    assert {k for k in metrics if not k.startswith("violation_")} <= set(UNITS)
    assert units == {k: UNITS[k] for k in metrics if not k.startswith("violation_")}
    assert read_plan(out).metrics.keys() == metrics.keys()


def test_every_numeric_batch_column_has_one_unit() -> None:
    assert not set(UNITS) & set(COLUMN_UNITS)
    numeric = [k for k, kind in {**RESULT_COLUMNS, **TASK_COLUMNS}.items() if kind.split()[0] in ("REAL", "INTEGER")]
    assert [k for k in numeric if column_unit(k) is None] == []
    assert display("goal_error") == ("mm", 1e3) and display("time_total", "ms") == ("ms", 1e3)
    assert display("penetration_max") == ("mm", 1e3) and display("n_pushes") == ("", 1.0)
    assert label("goal err", "goal_error") == "goal err [mm]" and label("pushes", "n_pushes") == "pushes"
    with pytest.raises(ValueError):
        display("goal_error", "ms")
    with pytest.raises(KeyError):
        display("no_such_metric")


ROWS_OF_A_BATCH = [
    {"task_id": "a", "variant": "qp/opt", "tool": "slope", "status": "solved", "time_total": 0.12,
     "cone_violation_max": 0.001, "reach_violation_max": 1e-4, "penetration_max": 0.0, "joint_limit_violation_max": 0.0,
     "obstacle_clearance_min": 0.004, "goal_error": 0.0011, "open_loop_status": "done", "open_loop_error": 0.0015,
     "open_loop_wall_time": 2.5, "closed_loop_status": "reached", "closed_loop_error": 0.0009,
     "closed_loop_replans": 2, "closed_loop_wall_time": 3.1},
    {"task_id": "b", "variant": "qp/opt", "tool": "slope", "status": "infeasible", "reason": "no", "time_total": 0.5},
]


def _report() -> str:
    console = Console(width=300, color_system=None, record=True)
    print_report(summarize(ROWS_OF_A_BATCH), top_reasons(ROWS_OF_A_BATCH), console)
    return console.export_text()


def test_the_batch_reports_unit_labels_come_from_the_units(monkeypatch: pytest.MonkeyPatch) -> None:
    text = _report()
    for head in ("cone [rad]", "reach [mm]", "penetr. [mm]", "joints [rad]", "clear. min [mm]", "goal err [mm]",
                 "t50 [ms]", "OL err [mm]", "CL err [mm]", "t OL/CL [s]", "OL <=2 mm", "CL <=5 mm"):
        assert head in text, head
    monkeypatch.setitem(UNITS, "reach_violation_max", "rad")  # the labels follow the table
    monkeypatch.setitem(COLUMN_UNITS, "penetration_max", "")
    monkeypatch.setitem(COLUMN_UNITS, "closed_loop_error", "rad")
    text = _report()
    assert "reach [rad]" in text and "reach [mm]" not in text
    assert "penetr. " in text and "penetr. [mm]" not in text
    assert "CL err [rad]" in text and "CL err [mm]" not in text


def test_the_paper_tables_rows_take_their_units_from_the_units() -> None:
    for key, _, u, scale in ROWS[1:]:
        assert (u, scale) == display(key, "ms" if key.startswith("time_") else None), key
    assert dict((k, (u, s)) for k, _, u, s in ROWS)["goal_error"] == ("mm", 1e3)
