"""Hostile datasets drawn by hypothesis (derandomized, bounded): a CSV cell, a header or a meta.yaml field
replaced by junk, a column group rescaled (other units), truth.yaml replaced by junk. Loading and
segmenting either works or raises a :class:`~tooltransfer.problems.dataset.DatasetError` whose one-line message
names the file (never another exception, never a traceback); a rescaled column group is always
refused."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_hostile_data_cases import copy_dataset

from tooltransfer.planner.learning.segmentation import segment
from tooltransfer.problems.dataset import DatasetError, load_dataset

SETTINGS = settings(derandomize=True, deadline=None, database=None, max_examples=25,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

JUNK = st.sampled_from(["", "nan", "inf", "-inf", "NaN", "abc", "1e309", "0x10", "True", "1;5", " ", "--1",
                        "1e-3", "\u00e9", "x" * 5000, '"1,2"', "1,2", "-0", "1e-320"])
META_VALUES = st.sampled_from([None, True, False, "x", -1, 0, 1e300, float("inf"), float("-inf"), float("nan"),
                               [], {}, [1, 2, 3], "../x", "y" * 3000, 0.5, 1e-12, "1e-3"])
META_FIELDS = st.sampled_from([("object_radius",), ("rates", "object_hz"), ("rates", "tool_hz"), ("platform", "a_t"),
                               ("platform", "base_xy"), ("platform", "base_yaw"), ("platform", "table_height"),
                               ("tool",), ("demonstrations",), ("units",), ("format",), ("scene",), ("extra",)])
GROUPS = {"object": (1, 2), "tool position": (3, 4), "heading": (5,), "joints": (6, 7, 8), "time": (0,)}


def _fresh(tmp_path: Path, tag: str) -> Path:
    folder = tmp_path / tag
    if folder.exists():
        shutil.rmtree(folder)
    return copy_dataset(folder, n=1)


def _outcome(folder: Path) -> str | None:
    """None if the dataset loads and segments; else the DatasetError's message (checked to be one line
    naming a file of the folder)."""
    try:
        ds = load_dataset(folder)
        tool = ds.tool()
        for d in ds.demonstrations:
            segment(d, tool, radius=float(ds.meta.object_radius))
    except DatasetError as exc:
        msg = str(exc)
        assert "\n" not in msg and len(msg) < 800, msg
        assert str(folder) in msg, msg
        return msg
    return None


@SETTINGS
@given(row=st.integers(1, 5000), col=st.integers(0, 8), junk=JUNK)
def test_junk_in_a_csv_cell(tmp_path: Path, row: int, col: int, junk: str) -> None:
    folder = _fresh(tmp_path, "cell")
    p = folder / "demo_00.csv"
    lines = p.read_text().splitlines()
    cells = lines[row].split(",")
    cells[col] = junk
    lines[row] = ",".join(cells)
    p.write_text("\n".join(lines) + "\n")
    msg = _outcome(folder)
    if msg is not None:
        assert "demo_00.csv" in msg


@SETTINGS
@given(col=st.integers(0, 8), junk=st.sampled_from(["", "T", "obj_x", "q1", "t", "q2 ", "\ufefft", "x,y"]))
def test_junk_in_the_header(tmp_path: Path, col: int, junk: str) -> None:
    folder = _fresh(tmp_path, "header")
    p = folder / "demo_00.csv"
    lines = p.read_text().splitlines()
    cells = lines[0].split(",")
    renamed = cells[col] != junk.strip()
    cells[col] = junk
    lines[0] = ",".join(cells)
    p.write_text("\n".join(lines) + "\n")
    msg = _outcome(folder)
    if renamed:  # a column missing or named twice
        assert msg is not None and "demo_00.csv: row 1" in msg


@SETTINGS
@given(path=META_FIELDS, value=META_VALUES)
def test_junk_in_a_meta_field(tmp_path: Path, path: tuple[str, ...], value: object) -> None:
    folder = _fresh(tmp_path, "meta")
    meta = yaml.safe_load((folder / "meta.yaml").read_text())
    node = meta
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    (folder / "meta.yaml").write_text(yaml.safe_dump(meta))
    msg = _outcome(folder)
    if msg is not None:
        assert "meta.yaml" in msg or ".csv" in msg or ".yaml" in msg


@SETTINGS
@given(group=st.sampled_from(sorted(GROUPS)), k=st.sampled_from([1e-3, 1e-2, 0.1, 10.0, 100.0, 1e3, 180 / np.pi]))
def test_a_column_group_in_other_units_is_refused(tmp_path: Path, group: str, k: float) -> None:
    folder = _fresh(tmp_path, "units")
    p = folder / "demo_00.csv"
    lines = p.read_text().splitlines()
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        for i in GROUPS[group]:
            if cells[i] != "":
                cells[i] = repr(float(cells[i]) * k)
        out.append(",".join(cells))
    p.write_text("\n".join(out) + "\n")
    msg = _outcome(folder)
    assert msg is not None and ("demo_00.csv" in msg or "meta.yaml: field tool" in msg), msg


@SETTINGS
@given(junk=st.one_of(st.sampled_from(["- 1\n", "42\n", "x: [\n", "'a'\n", "demo_00: 3\n", "demo_00: {pushes: 3}\n",
                                       "demo_00: {pushes: [{face: 1}]}\n", "? [a]\n: 1\n", "\x00\x01", "null\n"]),
                      st.text(max_size=200)))
def test_junk_as_truth_yaml(tmp_path: Path, junk: str) -> None:
    folder = _fresh(tmp_path, "truth")
    (folder / "truth.yaml").write_text(junk)
    msg = _outcome(folder)
    if msg is not None:
        assert "truth.yaml" in msg, msg
