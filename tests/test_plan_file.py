"""Plan files: round trip and refusal of other versions or inconsistent content."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tooltransfer.planner.planning.plan import Plan, PlanFileError, Segment, read_plan


def small_plan() -> Plan:
    t = np.linspace(0, 1, 5)
    return Plan(status="solved", variant={"oe": "qp", "ss": "arch"}, task={"name": "x"}, platform={}, object={},
                tool={}, obstacles=[], t=t, object_xy=np.zeros((5, 2)), tool_pose=np.ones((5, 3)),
                joints=np.zeros((5, 3)), phase=("approach", "push", "push", "switch", "retreat"),
                face=(None, "left", "left", None, None), pushes=(Segment("push", 0.25, 0.5, ("left",)),),
                metrics={"goal_error": 0.0, "switch_clearance_min": float("inf")})


def test_round_trip(tmp_path: Path) -> None:
    p = small_plan().write(tmp_path / "p.json")
    back = read_plan(p)
    assert np.array_equal(back.t, small_plan().t) and back.face == small_plan().face
    assert back.pushes[0].faces == ("left",) and back.metrics["switch_clearance_min"] == float("inf")


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d.update(format="tooltransfer.plan/0"), "format"),
        (lambda d: d["samples"]["t"].pop(), "samples.object_xy"),
        (lambda d: d["samples"]["phase"].__setitem__(0, "fly"), "samples.phase"),
        (lambda d: d["samples"]["t"].reverse(), "samples.t"),
    ],
)
def test_refuses_other_versions_and_inconsistent_files(tmp_path: Path, change, field: str) -> None:
    p = small_plan().write(tmp_path / "p.json")
    doc = json.loads(p.read_text())
    change(doc)
    p.write_text(json.dumps(doc))
    with pytest.raises(PlanFileError) as err:
        read_plan(p)
    assert field in err.value.field


def test_the_metrics_units_beside_them_and_plan_files_without_them(tmp_path: Path) -> None:
    p = small_plan().write(tmp_path / "p.json")
    doc = json.loads(p.read_text())
    assert doc["metric_units"] == {"goal_error": "m", "switch_clearance_min": "m"}
    del doc["metric_units"]  # a plan file written before metric_units
    p.write_text(json.dumps(doc))
    assert read_plan(p).metrics == read_plan(small_plan().write(tmp_path / "q.json")).metrics


@pytest.mark.parametrize(
    ("units", "field"),
    [
        (["m"], "metric_units"),
        ({"goal_error": "mm"}, "metric_units.goal_error"),
        ({"goal_error": 1}, "metric_units.goal_error"),
        ({"goal_error": "rad"}, "metric_units.goal_error"),
        ({"no_such_metric": "m"}, "metric_units.no_such_metric"),
    ],
)
def test_refuses_metric_units_that_are_not_the_metrics(tmp_path: Path, units: object, field: str) -> None:
    p = small_plan().write(tmp_path / "p.json")
    doc = json.loads(p.read_text())
    doc["metric_units"] = units
    p.write_text(json.dumps(doc))
    with pytest.raises(PlanFileError) as err:
        read_plan(p)
    assert err.value.field == f"{p}: {field}"
