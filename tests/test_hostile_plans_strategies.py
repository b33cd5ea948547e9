"""Hostile plan files drawn by hypothesis (derandomized, bounded): a sample, a metric, a segment or a
top-level field replaced by junk of any JSON type, arrays cut short, time scaled. Reading and checking
the plan either passes or raises an :class:`~tooltransfer.errors.InputError` whose one-line message names the
file (never another exception); a plan timed faster than its tool's limits never passes."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tooltransfer.errors import InputError
from tooltransfer.planner.execution.simulate import check_plan
from tooltransfer.planner.planning.plan import read_plan

ROOT = Path(__file__).resolve().parents[1]
SETTINGS = settings(derandomize=True, deadline=None, database=None, max_examples=30,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
JUNK = st.one_of(st.none(), st.booleans(), st.integers(-10**20, 10**20), st.sampled_from(
    [float("nan"), float("inf"), -1e308, 1e-320, 0.0, -0.0, 1e6]), st.text(max_size=20),
    st.lists(st.integers(0, 3), max_size=4), st.dictionaries(st.text(max_size=3), st.integers(0, 3), max_size=2))


@pytest.fixture(scope="module")
def plan_doc(tmp_path_factory: pytest.TempPathFactory) -> dict:
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task

    path = ROOT / "problems" / "paper" / "fig14_safety_margin.yaml"
    plan = solve(load_task(path), path)
    assert plan.status == "solved", plan.reason
    return json.loads(plan.write(tmp_path_factory.mktemp("plan") / "plan.json").read_text())


def _outcome(tmp_path: Path, doc: dict) -> str | None:
    p = tmp_path / "plan.json"
    p.write_text(json.dumps(doc))
    try:
        plan = read_plan(p)
        if plan.status in ("solved", "violated"):
            check_plan(plan, str(p))
    except InputError as exc:
        msg = str(exc)
        assert msg.startswith(str(p)) and "\n" not in msg and len(msg) < 800, msg
        return msg
    return None


@SETTINGS
@given(key=st.sampled_from(["t", "object_xy", "tool_pose", "joints", "phase", "face"]), index=st.integers(0, 400),
       sub=st.integers(0, 2), junk=JUNK)
def test_junk_in_a_sample(plan_doc: dict, tmp_path: Path, key: str, index: int, sub: int, junk: object) -> None:
    d = copy.deepcopy(plan_doc)
    cell = d["samples"][key]
    if isinstance(cell[index], list):
        cell[index][sub % len(cell[index])] = junk
    else:
        cell[index] = junk
    _outcome(tmp_path, d)


@SETTINGS
@given(key=st.sampled_from(["status", "reason", "variant", "task", "platform", "object", "tool", "obstacles",
                            "metrics", "samples", "pushes", "switches", "format"]), junk=JUNK)
def test_junk_as_a_top_level_field(plan_doc: dict, tmp_path: Path, key: str, junk: object) -> None:
    d = copy.deepcopy(plan_doc)
    d[key] = junk
    _outcome(tmp_path, d)


@SETTINGS
@given(where=st.sampled_from(["metrics", "pushes", "switches", "task"]), name=st.text(min_size=1, max_size=12),
       junk=JUNK)
def test_junk_inside_a_mapping(plan_doc: dict, tmp_path: Path, where: str, name: str, junk: object) -> None:
    d = copy.deepcopy(plan_doc)
    target = d[where][0] if isinstance(d[where], list) and d[where] else d[where]
    if isinstance(target, dict):
        key = sorted(target)[hash(name) % len(target)] if name.startswith("_") else name
        target[key] = junk
    _outcome(tmp_path, d)


@SETTINGS
@given(key=st.sampled_from(["t", "object_xy", "tool_pose", "joints", "phase", "face"]), keep=st.integers(0, 50))
def test_an_array_cut_short(plan_doc: dict, tmp_path: Path, key: str, keep: int) -> None:
    d = copy.deepcopy(plan_doc)
    d["samples"][key] = d["samples"][key][:keep]
    assert _outcome(tmp_path, d) is not None


@SETTINGS
@given(k=st.floats(1e-6, 0.7))
def test_a_plan_timed_faster_than_the_limits_never_passes(plan_doc: dict, tmp_path: Path, k: float) -> None:
    d = copy.deepcopy(plan_doc)
    d["samples"]["t"] = [k * t for t in d["samples"]["t"]]
    msg = _outcome(tmp_path, d)
    assert msg is not None and ("max_tool_speed" in msg or "max_tool_accel" in msg), msg
