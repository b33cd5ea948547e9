"""Hostile input, class 1 of issue 16 (unbounded sizes and rates): every task option has a bound a
user reads in the JSON schema (``tooltransfer schema``), every value beyond it is refused naming
the field (exit 2, one line, at once), the push-sequence search and the plan's duration are capped
for the task's tool and timing, a solve at the slowest limits stays within them, and ``simulate``
refuses a plan stretched 10^4 in time at once. Hypothesis strategies are derandomized.
"""

from __future__ import annotations

import copy
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tooltransfer.planner.apps.cli import main
from tooltransfer.problems.task import (
    MAX_PLAN_DURATION,
    MAX_SEARCH_STEPS,
    Task,
    TaskFileError,
    push_search_steps,
    task_from_dict,
)

ROOT = Path(__file__).resolve().parent.parent
TRANSFER = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
BASE: dict[str, Any] = {
    "name": "sizes", "tool": "slope", "start": [0.045, 0.12], "target": [-0.052, 0.19],
    "obstacles": [{"kind": "disc", "centre": [0.015, 0.125], "radius": 0.005}],
    "skills": {"dataset": str(ROOT / "problems" / "data" / "finger_demos")},
    "object": {"mechanics": {"mu": 0.8, "c": 0.59}},
}
SETTINGS = settings(derandomize=True, deadline=None, max_examples=60,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


def _leaves(schema: dict, defs: dict, path: tuple[str, ...] = (), in_array: bool = False) -> list[tuple]:
    """(kind, path, schema, inside an array) of every leaf of a JSON schema."""
    if "$ref" in schema:
        schema = {**defs[schema["$ref"].rsplit("/", 1)[1]], **{k: v for k, v in schema.items() if k != "$ref"}}
    out: list[tuple] = []
    for alt in schema.get("anyOf", []) + schema.get("oneOf", []):
        out += _leaves(alt, defs, path, in_array)
    kind = schema.get("type")
    if kind == "object":
        for key, sub in schema.get("properties", {}).items():
            out += _leaves(sub, defs, (*path, key), in_array)
        if schema.get("additionalProperties") not in (None, False):
            out.append(("free-form", path, schema, in_array))
    elif kind == "array":
        out.append(("array", path, schema, in_array))
        for i, sub in enumerate(schema.get("prefixItems", [])):
            out += _leaves(sub, defs, (*path, f"[{i}]"), True)
        if isinstance(schema.get("items"), dict):
            out += _leaves(schema["items"], defs, (*path, "[i]"), True)
    elif kind in ("number", "integer", "string"):
        out.append((kind, path, schema, in_array))
    return out


def _task_leaves() -> list[tuple]:
    s = Task.model_json_schema()
    return _leaves(s, s.get("$defs", {}))


def test_every_task_option_has_a_bound_in_the_schema() -> None:
    unbounded = []
    for kind, path, s, _ in _task_leaves():
        name = ".".join(path)
        if kind in ("number", "integer"):
            if not ({"maximum", "exclusiveMaximum"} & s.keys() and {"minimum", "exclusiveMinimum"} & s.keys()):
                unbounded.append(name)
        elif kind == "string" and "maxLength" not in s and "enum" not in s and "const" not in s:
            unbounded.append(name)
        elif kind == "array" and "maxItems" not in s and "prefixItems" not in s:
            unbounded.append(name)
        elif kind == "free-form":
            unbounded.append(name)
    assert not unbounded, unbounded


def test_every_batch_number_and_list_is_bounded() -> None:
    from tooltransfer.planner.apps.batch.spec import BatchSpec

    s = BatchSpec.model_json_schema()
    bad = [".".join(p) for kind, p, sch, _ in _leaves(s, s.get("$defs", {}))
           if (kind in ("number", "integer") and not {"maximum", "exclusiveMaximum"} & sch.keys())
           or (kind == "array" and "maxItems" not in sch and "prefixItems" not in sch)
           or (kind == "string" and p != ("task",) and not {"maxLength", "enum", "const"} & sch.keys())]
    assert not bad, bad


#: an inline tool (the slope's outline and faces) for the options of inline tools
INLINE = {"name": "inline", "a_t": 0.028,
          "outline": [[-0.006, -0.03], [0.006, -0.03], [0.006, 0.0104], [0.0, 0.0104], [-0.006, 0.0]],
          "faces": [{"name": "left", "segment": [[-0.006, 0.0], [-0.006, -0.005]], "push_angle": "pi",
                     "theta_b": "pi/6"}]}


def _set(data: dict, path: tuple[str, ...], value: object) -> dict:
    d = copy.deepcopy(data)
    if path[0] == "tool":
        d["tool"] = copy.deepcopy(INLINE)
    node = d
    for k in path[:-1]:
        node = node.setdefault(k, {})
    node[path[-1]] = value
    return d


def _beyond(s: dict, kind: str) -> list[float]:
    """Values just outside the schema's bounds."""
    out: list[float] = []
    step = 1 if kind == "integer" else None
    if "maximum" in s:
        hi = s["maximum"]
        out.append(hi + (step or max(abs(hi) * 1e-3, 1e-9)))
    if "exclusiveMaximum" in s:
        out.append(s["exclusiveMaximum"])
    if "minimum" in s:
        lo = s["minimum"]
        out.append(lo - (step or max(abs(lo) * 1e-3, 1e-9)))
    if "exclusiveMinimum" in s:
        out.append(s["exclusiveMinimum"])
    return [int(v) if kind == "integer" else float(v) for v in out]


NUMBER_OPTIONS = [(p, s, kind) for kind, p, s, in_array in _task_leaves()
                  if kind in ("number", "integer") and not in_array and p != ("format",)]


def test_the_options_checked_include_the_issue_examples() -> None:
    names = {".".join(p) for p, _, _ in NUMBER_OPTIONS}
    assert {"oe.n_basis", "oe.n_samples", "oe.segments", "oe.max_pushes", "oe.candidates", "oe.max_contacts",
            "ss.n_knots", "timing.max_tool_speed", "timing.max_tool_accel", "timing.approach_distance"} <= names


@pytest.mark.parametrize(("path", "schema", "kind"), NUMBER_OPTIONS, ids=[".".join(p) for p, _, _ in NUMBER_OPTIONS])
def test_values_beyond_the_schema_bounds_are_refused_naming_the_field(path, schema, kind) -> None:
    for value in _beyond(schema, kind):
        with pytest.raises(TaskFileError) as exc:
            task_from_dict(_set(BASE, path, value), "t.yaml")
        assert f"t.yaml: {'.'.join(path)}: expected" in str(exc.value), (value, str(exc.value))


@SETTINGS
@given(st.sampled_from(NUMBER_OPTIONS), st.data())
def test_any_value_is_taken_iff_the_schema_bounds_allow_it(option, data: st.DataObject) -> None:
    path, s, kind = option
    if kind == "integer":
        value: float = data.draw(st.one_of(st.integers(-10, 300), st.integers(-10**12, 10**12)))
    else:
        value = data.draw(st.one_of(st.floats(-1e-6, 0.3), st.floats(-1e12, 1e12, allow_nan=False),
                                    st.sampled_from([1e-9, 1e-7, 1e3, 1e6, 1e300])))
    inside = (value <= s.get("maximum", np.inf) and value < s.get("exclusiveMaximum", np.inf)
              and value >= s.get("minimum", -np.inf) and value > s.get("exclusiveMinimum", -np.inf))
    try:
        task_from_dict(_set(BASE, path, value), "t.yaml")
    except TaskFileError as exc:
        field = ".".join(path)
        # inside its own bounds a value may still be refused by a check across fields that names it
        # (k > 1 against the tube, a search or a plan too large), never by another field's bound
        assert not inside or field in str(exc) or "timing" in str(exc) or "oe.max_pushes" in str(exc), str(exc)
        assert len(str(exc)) < 400
    else:
        assert inside, (path, value)


@pytest.mark.parametrize(("field", "text"), [
    ("oe.n_basis", "oe: {n_basis: 100000}"), ("ss.n_knots", "ss: {n_knots: 1000000}"),
    ("oe.n_samples", "oe: {n_samples: 1e7}"), ("oe.segments", "oe: {segments: 1e6}"),
    ("oe.max_pushes", "oe: {max_pushes: 1000}"), ("oe.candidates", "oe: {candidates: 1000}"),
    ("oe.max_contacts", "oe: {max_contacts: 100}"), ("timing.max_tool_speed", "timing: {max_tool_speed: 1.0e-7}"),
    ("timing.max_tool_accel", "timing: {max_tool_accel: 1.0e-9}"),
    ("timing.approach_distance", "timing: {approach_distance: 1000}"),
    ("obstacles", "obstacles: [" + ", ".join(["{kind: disc, centre: [0.3, 0.3], radius: 0.001}"] * 33) + "]"),
    ("name", "name: " + "n" * 101),
])
def test_the_issue_examples_exit_2_at_once_naming_the_field(tmp_path: Path, capsys, field: str, text: str) -> None:
    data = yaml.safe_load(TRANSFER.read_text())
    data["skills"] = BASE["skills"]
    key = text.split(":", 1)[0]
    data.pop(key, None)
    p = tmp_path / "task.yaml"
    p.write_text(yaml.safe_dump(data) + text + "\n")
    start = time.perf_counter()
    assert main(["solve", str(p), "--json"]) == 2
    assert time.perf_counter() - start < 10
    err = capsys.readouterr().err
    assert f"{p}: {field}:" in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


@pytest.mark.parametrize(("change", "field"), [
    ({"obstacles": [{"kind": "polygon", "vertices": [[np.cos(a) * 0.01 + 0.3, np.sin(a) * 0.01 + 0.3]
                                                     for a in np.linspace(0, 6.2, 65)]}]}, "obstacles[0].vertices"),
    ({"fixed_points": [[0.0, 0.15]] * 65}, "fixed_points"),
    ({"description": "d" * 4001}, "description"),
    ({"tool": {"name": "many", "a_t": 0.02, "outline": [[np.cos(a) * 0.01, np.sin(a) * 0.01]
                                                         for a in np.linspace(0, 6.2, 257)],
               "faces": [{"name": "f", "segment": [[0, 0], [0.01, 0]], "push_angle": 1.5, "theta_b": 0.3}]}},
     "tool.outline"),
    ({"skills": {"dataset": "d" * 5000}}, "skills.dataset"),
])
def test_lists_and_texts_are_bounded(change: dict, field: str) -> None:
    with pytest.raises(TaskFileError) as exc:
        task_from_dict({**BASE, **json.loads(json.dumps(change))}, "t.yaml")
    assert f"t.yaml: {field}:" in str(exc.value) and len(str(exc.value)) < 400


# --- the push-sequence search and the plan's duration, across fields -------------------------------

@pytest.mark.parametrize(("tool", "max_pushes", "segments", "ok"), [
    ("slope", 8, 50, True), ("t_shape", 6, 10, True), ("t_shape", 7, 10, False), ("t_shape", 8, 10, False),
    ("l_shape", 6, 50, False), ("i_shape", 8, 10, True), ("i_shape", 8, 50, False),
])
def test_the_push_sequence_search_is_capped_for_the_tool(tool: str, max_pushes: int, segments: int, ok: bool) -> None:
    data = {**BASE, "tool": tool, "oe": {"max_pushes": max_pushes, "segments": segments}}
    if ok:
        task_from_dict(data, "t.yaml")
        return
    with pytest.raises(TaskFileError, match=r"t\.yaml: oe\.max_pushes: expected a push-sequence search of at most"):
        task_from_dict(data, "t.yaml")


def test_an_inline_tool_of_many_faces_has_a_smaller_search() -> None:
    faces = [{"name": f"f{i}", "segment": [[np.cos(a) * 0.01, np.sin(a) * 0.01], [np.cos(b) * 0.01, np.sin(b) * 0.01]],
              "push_angle": float(a + b) / 2, "theta_b": 0.3}
             for i, (a, b) in enumerate(zip(np.linspace(0, 2 * np.pi, 9)[:-1], np.linspace(0, 2 * np.pi, 9)[1:],
                                            strict=True))]
    outline = [f["segment"][0] for f in faces]
    tool = json.loads(json.dumps({"name": "octagon", "a_t": 0.02, "outline": outline, "faces": faces}))
    task_from_dict({**BASE, "tool": tool}, "t.yaml")  # max_pushes 4 of 8 faces: within the cap
    with pytest.raises(TaskFileError, match=r"oe\.max_pushes"):
        task_from_dict({**BASE, "tool": tool, "oe": {"max_pushes": 5}}, "t.yaml")


@SETTINGS
@given(st.integers(1, 8), st.integers(1, 8), st.integers(1, 50))
def test_the_search_cap_follows_its_model(n_faces: int, max_pushes: int, segments: int) -> None:
    steps = push_search_steps(n_faces, max_pushes, segments)
    assert steps >= n_faces
    if max_pushes > 1:  # more pushes or segments never make the search cheaper
        assert steps >= push_search_steps(n_faces, max_pushes - 1, segments)
    if segments > 1:
        assert steps >= push_search_steps(n_faces, max_pushes, segments - 1)


def test_the_largest_search_allowed_takes_seconds_not_minutes() -> None:
    from tooltransfer.planner.planning.oe.sequence_proxy import ranked_sequences

    f, k = 4, 10
    p = max(p for p in range(1, 9) if push_search_steps(f, p, k) <= MAX_SEARCH_STEPS)
    start = time.perf_counter()
    ranked_sequences(np.random.default_rng(0).random((k, f)), [str(i) for i in range(f)], p, 1e-7)
    assert time.perf_counter() - start < 8.0


@pytest.mark.parametrize(("timing", "field"), [
    ({"max_tool_speed": 0.005}, "timing.max_tool_speed"),
    ({"max_tool_speed": 1.0, "max_tool_accel": 0.005}, None),  # 14 m under 0.005 m/s^2: 127 s, taken
    ({"max_tool_speed": 0.05}, None),  # 14 m at 50 mm/s: 530 s, taken
])
def test_the_plan_duration_is_capped_naming_the_timing_field(timing: dict, field: str | None) -> None:
    data = {**BASE, "start": [-5.0, -5.0], "target": [5.0, 5.0], "obstacles": [], "timing": timing}
    if field is None:
        task_from_dict(data, "t.yaml")
        return
    with pytest.raises(TaskFileError) as exc:
        task_from_dict(data, "t.yaml")
    assert f"t.yaml: {field}: expected limits under which the plan lasts at most {MAX_PLAN_DURATION:g} s" in str(
        exc.value)


def test_batch_values_beyond_their_bounds_are_refused_naming_the_field() -> None:
    from tooltransfer.planner.apps.batch.spec import BatchFileError, batch_from_dict

    base = {"name": "b", "count": 1, "tools": ["slope"], "dataset": "."}
    for change, field in [({"timeout": 1e9}, "timeout"), ({"distance": [0.04, 50]}, "distance[1]"),
                          ({"seed": 2**70}, "seed"), ({"simulate": {"timeout": 1e7}}, "simulate.timeout"),
                          ({"obstacles": {"radius": [0.001, 2]}}, "obstacles.radius[1]"),
                          ({"count": 10**7}, "count"), ({"name": "n" * 81}, "name")]:
        with pytest.raises(BatchFileError) as exc:
            batch_from_dict({**base, **change}, "b.yaml")
        assert f"b.yaml: {field}: expected" in str(exc.value), str(exc.value)


# --- a solve at the slowest limits, and a plan stretched 10^4 in time -------------------------------

@pytest.fixture(scope="module")
def slow_plan(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from tooltransfer.planner.planning.solve import solve

    data = {**BASE, "variants": {"oe": "qp", "ss": "arch"},
            "timing": {"max_tool_speed": 0.005, "max_tool_accel": 0.005, "approach_distance": 0.1}}
    task = task_from_dict(data, "slow.yaml")
    start = time.perf_counter()
    plan = solve(task, ROOT / "problems" / "paper" / "x.yaml")
    assert time.perf_counter() - start < 120  # learning the skills included, the first time
    assert plan.status == "solved", plan.reason
    assert plan.t[-1] <= MAX_PLAN_DURATION and plan.t.size <= MAX_PLAN_DURATION * 100 + 20 * task.oe.n_samples
    return plan.write(tmp_path_factory.mktemp("slow") / "plan.json")


def test_a_plan_stretched_ten_thousand_times_is_refused_at_once(slow_plan: Path, tmp_path: Path, capsys) -> None:
    doc = json.loads(slow_plan.read_text())
    doc["samples"]["t"] = [t * 1e4 for t in doc["samples"]["t"]]
    p = tmp_path / "stretched.json"
    p.write_text(json.dumps(doc))
    capsys.readouterr()
    start = time.perf_counter()
    assert main(["simulate", str(p), "--json"]) == 2
    assert time.perf_counter() - start < 10
    err = capsys.readouterr().err
    assert str(p) in err and "samples.t" in err and len(err.strip().splitlines()) == 1
