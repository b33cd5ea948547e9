"""Task files: schema, loading, errors that name the file, the field path and what was expected."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from tooltransfer.problems.task import (
    TaskFileError,
    load_task,
    task_from_dict,
    task_json_schema,
    task_obstacles,
    task_platform,
)
from tooltransfer.problems.task import task_tool as build_tool
from tooltransfer.tools import Disc

BASE = {"name": "t", "tool": "slope", "start": [0.05, 0.12], "target": [-0.07, 0.18], "skills": {"dataset": "d"}}


def write(tmp_path: Path, data: object) -> Path:
    p = tmp_path / "task.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def test_defaults_and_runtime_objects(tmp_path: Path) -> None:
    data = {**BASE, "obstacles": [{"kind": "disc", "centre": [0.0, 0.16], "radius": 0.01},
                                  {"kind": "polygon", "vertices": [[0.0, 0.09], [0.02, 0.09], [0.02, 0.1]]}]}
    task = load_task(write(tmp_path, data))
    assert task.variants.oe == "qp" and task.variants.ss == "opt"
    tool = build_tool(task)
    assert tool.name == "slope"
    assert task_platform(task, tool).a_t == tool.a_t
    obs = task_obstacles(task)
    assert isinstance(obs[0], Disc) and obs[1].area == pytest.approx(1e-4)


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        ({"start": [0.1, float("nan")]}, "start[1]", "finite"),
        ({"obstacles": [{"kind": "disc", "centre": [0, 0.1], "radius": -1}]}, "obstacles[0].radius", "greater than 0"),
        ({"obstacles": [{"kind": "polygon", "vertices": [[0, 0], [1, 1], [1, 0], [0, 1]]}]}, "obstacles[0].vertices",
         "simple polygon"),
        ({"obstacles": [{"kind": "polygon", "vertices": [[0, 0], [2, 0], [1, 0.2], [1, 1], [0, 1]]}]},
         "obstacles[0].vertices", "convex"),
        ({"tool": "hammer"}, "tool", "library tool"),
        ({"target": BASE["start"]}, "target", "zero-length"),
        ({"skills": {}}, "skills", "exactly one"),
        ({"oe": {"k": 2}}, "oe.k", "less than 1"),
        ({"colour": "red"}, "colour", "Extra inputs"),
        ({"start": "here"}, "start", "tuple"),
        ({"variants": {"oe": "magic"}}, "variants.oe", "'mapping' or 'qp'"),
    ],
)
def test_errors_name_the_file_and_field(tmp_path: Path, change: dict, field: str, words: str) -> None:
    path = write(tmp_path, {**BASE, **change})
    with pytest.raises(TaskFileError) as err:
        load_task(path)
    assert err.value.field == f"{path}: {field}"
    assert words in str(err.value)


def test_inline_tool_is_checked_like_a_library_tool(tmp_path: Path) -> None:
    tool = {"name": "x", "a_t": 0.02, "outline": [[0, 0], [0.1, 0], [0, 0.1]],
            "faces": [{"name": "f", "segment": [[0, 0], [0.1, 0]], "push_angle": "pi/2", "theta_b": 0.3}]}
    with pytest.raises(TaskFileError) as err:
        load_task(write(tmp_path, {**BASE, "tool": tool}))
    assert err.value.field.endswith("tool.faces[0].push_angle")
    tool["faces"][0]["push_angle"] = "-pi/2"
    assert build_tool(load_task(write(tmp_path, {**BASE, "tool": tool}))).face_names == ("f",)


def test_yaml_syntax_error_has_line_and_column(tmp_path: Path) -> None:
    p = tmp_path / "bad.yaml"
    p.write_text("name: t\nstart: [0.1, 0.2\ntarget: [0, 0]\n")
    with pytest.raises(TaskFileError) as err:
        load_task(p)
    assert "line 3, column" in err.value.field


def test_missing_file_and_non_mapping(tmp_path: Path) -> None:
    with pytest.raises(TaskFileError, match="readable"):
        load_task(tmp_path / "nope.yaml")
    with pytest.raises(TaskFileError, match="mapping"):
        task_from_dict([1, 2], "list.yaml")


def test_json_schema_describes_units() -> None:
    schema = json.loads(task_json_schema())
    assert schema["title"] == "Task"
    assert "[m]" in json.dumps(schema["properties"]["safety_margin"])
    assert np.isclose(schema["$defs"]["PlatformSpec"]["properties"]["base_yaw"]["default"], np.pi / 2)
