"""Every plan metric has its unit in one table (tooltransfer.planner.metric_units), which the command
line's summary uses instead of guessing from the name."""

from __future__ import annotations

import json
from pathlib import Path

from tooltransfer.planner.batch.execute import METRIC_COLUMNS
from tooltransfer.planner.cli import main
from tooltransfer.planner.metric_units import UNITS, shown, unit
from tooltransfer.planner.solve import HARD_CHECKS

TRANSFER = Path(__file__).resolve().parents[1] / "problems" / "paper" / "transfer_tool2.yaml"


def test_a_solved_plans_metrics_all_have_a_unit(tmp_path: Path, capsys) -> None:
    out = tmp_path / "plan.json"
    assert main(["solve", str(TRANSFER), "--variant", "mapping/arch", "-o", str(out), "--json"]) in (0, 1)
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
