"""Tool files: the shipped library, YAML round trips, and errors that name the field."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from tooltransfer.errors import ToolTransferError
from tooltransfer.tools import (
    Face,
    Tool,
    ToolSpecError,
    UnknownFaceError,
    UnknownToolError,
    dump_tool,
    library_names,
    load_library,
    load_tool,
    tool_from_dict,
    tool_to_dict,
)
from tooltransfer.tools.library import parse_angle

PAPER = {"finger": 0.026, "slope": 0.028}


def test_library_holds_the_required_tools() -> None:
    assert {"finger", "slope", "t_shape", "trapezoid", "l_shape", "i_shape"} <= set(library_names())
    for name, tool in load_library().items():
        assert tool.name == name
        assert tool.notes and tool.description


def test_paper_tools_have_table_ii_numbers() -> None:
    finger = load_tool("finger")
    assert finger.a_t == PAPER["finger"]
    x0, _, x1, y1 = finger.outline.bounds
    assert x1 - x0 == pytest.approx(0.012)  # width 12 mm
    assert y1 == pytest.approx(0.006)  # head radius 6 mm about the tool centre point
    assert finger.face("left").length == pytest.approx(0.010)
    assert finger.face("upper").push_angle == pytest.approx(np.pi / 2)
    assert finger.face("left").push_angle == pytest.approx(np.pi)
    slope = load_tool("slope")
    assert slope.a_t == PAPER["slope"]
    assert slope.face("left").length == pytest.approx(0.005)
    inc = slope.face("inclined")
    d = inc.end - inc.start
    assert np.arctan2(d[1], d[0]) == pytest.approx(np.pi / 3)
    assert inc.push_angle == pytest.approx(0.75 * np.pi)


def test_faces_have_outward_normals() -> None:
    for tool in load_library().values():
        for f in tool.faces:
            mid = 0.5 * (f.start + f.end)
            assert not tool.outline.contains(shapely.Point(mid + 1e-6 * f.normal))
            assert tool.outline.contains(shapely.Point(mid - 1e-6 * f.normal))


@pytest.mark.parametrize("name", library_names())
def test_library_tools_round_trip_through_yaml(name: str, tmp_path: Path) -> None:
    tool = load_tool(name)
    path = tmp_path / f"{name}_copy.yaml"
    dump_tool(tool, path)
    again = load_tool(path)
    assert again == tool
    assert tool_to_dict(again) == tool_to_dict(tool)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(
    w=st.floats(0.002, 0.05),
    h=st.floats(0.002, 0.05),
    cx=st.floats(-0.02, 0.02),
    cy=st.floats(-0.02, 0.02),
    push=st.floats(-0.5, 0.5),
    theta_b=st.floats(0.01, 0.9),
    s0=st.floats(0.0, 1.0),
)
def test_random_tools_round_trip(
    w: float, h: float, cx: float, cy: float, push: float, theta_b: float, s0: float
) -> None:
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
    tool = Tool(
        name="box",
        outline=shapely.Polygon([(x0, y0), (x1, y0), (x1, y1), (x0, y1)]),
        faces=(
            Face(
                "top",
                np.array([x0, y1]),
                np.array([x1, y1]),
                np.pi / 2 + push * (1 - theta_b),
                theta_b,
                (s0, 1.0),
            ),
        ),
        a_t=0.03,
        description="d",
        notes="n",
    )
    assert tool_from_dict(yaml.safe_load(dump_tool(tool))) == tool


def test_unknown_names_list_valid_ones() -> None:
    with pytest.raises(UnknownToolError) as err:
        load_tool("hammer")
    assert "finger" in str(err.value) and "trapezoid" in str(err.value)
    assert isinstance(err.value, ToolTransferError)
    with pytest.raises(UnknownFaceError, match="upper, left"):
        load_tool("finger").face("bottom")


def test_missing_file_is_a_spec_error(tmp_path: Path) -> None:
    with pytest.raises(ToolSpecError, match="readable tool file, got No such file"):
        load_tool(tmp_path / "nope.yaml")


@pytest.mark.parametrize(
    ("text", "expr"),
    [
        ("pi/2", np.pi / 2),
        ("0.75*pi", 0.75 * np.pi),
        ("-pi/6", -np.pi / 6),
        ("3*pi/4", 0.75 * np.pi),
        ("pi", np.pi),
        ("2 pi / 3", 2 * np.pi / 3),
        (0.5, 0.5),
    ],
)
def test_angle_expressions(text: str | float, expr: float) -> None:
    assert parse_angle(text, "t", "f") == pytest.approx(expr, abs=1e-15)


def _finger_dict() -> dict:
    return tool_to_dict(load_tool("finger"))


def _expect(tmp_path: Path, data: dict, field: str, words: str) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(ToolSpecError) as err:
        load_tool(path)
    assert err.value.field == field, str(err.value)
    assert words in str(err.value)
    assert field in str(err.value)


def test_self_intersecting_outline(tmp_path: Path) -> None:
    d = _finger_dict()
    d["outline"] = [[0, 0], [0.01, 0.01], [0.01, 0], [0, 0.01]]  # a bow tie
    _expect(tmp_path, d, "outline", "not a simple polygon")


def test_face_off_the_outline(tmp_path: Path) -> None:
    d = _finger_dict()
    d["faces"][1]["segment"] = [[-0.0059, 0.0], [-0.0059, -0.010]]  # 0.1 mm inside
    _expect(tmp_path, d, "faces[1].segment", "does not lie on one straight edge")
    d = _finger_dict()
    d["faces"][0]["segment"] = [[-0.006, -0.03], [0.006, 0.006]]  # across the tool
    _expect(tmp_path, d, "faces[0].segment", "does not lie")


@pytest.mark.parametrize("bad", [0.0, -0.1, float(np.pi / 2), 2.0, "pi"])
def test_theta_b_out_of_range(tmp_path: Path, bad: float | str) -> None:
    d = _finger_dict()
    d["faces"][0]["theta_b"] = bad
    _expect(tmp_path, d, "faces[0].theta_b", "(0, pi/2)")


@pytest.mark.parametrize(
    ("path", "field"),
    [
        ((), "name"),
        ((), "a_t"),
        ((), "outline"),
        (("faces", 0), "faces[0].theta_b"),
        (("faces", 1), "faces[1].push_angle"),
        (("faces", 1), "faces[1].segment"),
        (("faces", 0), "faces[0].name"),
    ],
)
def test_missing_fields(tmp_path: Path, path: tuple, field: str) -> None:
    d = _finger_dict()
    target = d
    for key in path:
        target = target[key]
    del target[field.split(".")[-1]]
    _expect(tmp_path, d, field, "missing required field")


def test_a_file_without_faces_gets_them_derived(tmp_path: Path) -> None:
    d = _finger_dict()
    del d["faces"]  # valid since issue 28: the faces are derived from the outline
    path = tmp_path / "bare.yaml"
    path.write_text(yaml.safe_dump(d), encoding="utf-8")
    tool = load_tool(path)
    assert tool.face_names == tuple(f"edge_{i}" for i in range(8))  # every edge of the finger is usable


def test_other_invalid_fields(tmp_path: Path) -> None:
    d = _finger_dict()
    d["faces"][0]["push_angle"] = 0.0  # pulls sideways: outside pi/2 of the upward normal
    _expect(tmp_path, d, "faces[0].push_angle", "outward normal")
    d = _finger_dict()
    d["faces"][1]["name"] = "upper"
    _expect(tmp_path, d, "faces[1].name", "duplicate")
    d = _finger_dict()
    d["faces"][0]["contact_range"] = [0.8, 0.2]
    _expect(tmp_path, d, "faces[0].contact_range", "s0 <= s1")
    d = _finger_dict()
    d["a_t"] = -0.01
    _expect(tmp_path, d, "a_t", "positive")
    d = _finger_dict()
    d["colour"] = "blue"
    _expect(tmp_path, d, "colour", "unknown field")
    d = _finger_dict()
    d["faces"] = []
    _expect(tmp_path, d, "faces", "non-empty")
    d = _finger_dict()
    d["outline"] = [[0, 0], [0.01, 0], [0.02, 0]]  # zero area
    _expect(tmp_path, d, "outline", "simple polygon")
    d = _finger_dict()
    d["outline"][2] = [0.006, "x"]
    _expect(tmp_path, d, "outline[2][1]", "number")


def test_invalid_yaml_syntax(tmp_path: Path) -> None:
    path = tmp_path / "broken.yaml"
    path.write_text("name: [unclosed\n", encoding="utf-8")
    with pytest.raises(ToolSpecError, match="line 2, column 1: valid YAML, got did not find expected"):
        load_tool(path)
