"""Hostile datasets (issue 16, class 5): datasets that lie about their columns, their tool, their units,
their platform or their ground truth, and files too large to read whole. Each case is a copy of two of
the committed demonstrations with one lie in it; loading and segmenting it (what ``segment``,
``learn`` and ``batch run`` do first) must end in a :class:`~tooltransfer.problems.dataset.DatasetError` (exit
code 2) whose one-line message names the file and the field, the row or the place, within seconds;
the unchanged copy loads and segments."""

from __future__ import annotations

import json
import shutil
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.learning.segmentation import load_fixed_points, segment
from tooltransfer.problems import dataset as dataset_module
from tooltransfer.problems.dataset import DatasetError, load_dataset

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "problems" / "data" / "finger_demos"
LIBRARY = ROOT / "tools" / "library"
DEG = 180.0 / np.pi


def copy_dataset(folder: Path, n: int = 2) -> Path:
    """The committed dataset trimmed to its first ``n`` demonstrations, with its truth.yaml."""
    folder.mkdir(parents=True)
    meta = yaml.safe_load((SRC / "meta.yaml").read_text())
    meta["demonstrations"] = meta["demonstrations"][:n]
    for name in meta["demonstrations"]:
        shutil.copy(SRC / name, folder / name)
    (folder / "meta.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))
    shutil.copy(SRC / "truth.yaml", folder / "truth.yaml")
    return folder


def edit_meta(folder: Path, change: Callable[[dict], object]) -> None:
    meta = yaml.safe_load((folder / "meta.yaml").read_text())
    change(meta)
    (folder / "meta.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))


def replace_meta(folder: Path, old: str, new: str) -> None:
    text = (folder / "meta.yaml").read_text()
    assert old in text
    (folder / "meta.yaml").write_text(text.replace(old, new, 1))


def scale(folder: Path, columns: tuple[int, ...], k: float, name: str = "demo_00.csv") -> None:
    """Multiply the given CSV columns (0 = t) of one demonstration by ``k``."""
    p = folder / name
    lines = p.read_text().splitlines()
    out = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        for i in columns:
            if cells[i] != "":
                cells[i] = repr(float(cells[i]) * k)
        out.append(",".join(cells))
    p.write_text("\n".join(out) + "\n")


def custom_tool(folder: Path, base: str, name: str, *, dx: float = 0.0, dy: float = 0.0, shrink: float = 1.0,
                a_t: float | None = None) -> None:
    """A tool YAML next to the data: a library tool moved by (dx, dy) [m] in its frame, or shrunk."""
    t = yaml.safe_load((LIBRARY / f"{base}.yaml").read_text())
    t["name"] = name
    if a_t is not None:
        t["a_t"] = a_t
    t["outline"] = [[shrink * x + dx, shrink * y + dy] for x, y in t["outline"]]
    for f in t["faces"]:
        f["segment"] = [[shrink * x + dx, shrink * y + dy] for x, y in f["segment"]]
    (folder / f"{name}.yaml").write_text(yaml.safe_dump(t))
    edit_meta(folder, lambda m: m.update(tool=f"{name}.yaml"))


def _header(folder: Path, header: str, extra: str = "", name: str = "demo_00.csv") -> None:
    p = folder / name
    lines = p.read_text().splitlines()
    lines[0] = header
    if extra:
        lines[1:] = [line + extra for line in lines[1:]]
    p.write_text("\n".join(lines) + "\n")


def _disjoint_streams(folder: Path) -> None:
    p = folder / "demo_00.csv"
    lines = p.read_text().splitlines()
    rows = [line.split(",") for line in lines[1:]]
    tool = [r for r in rows if r[3] != ""]
    obj = [r for r in rows if r[1] != ""]
    shift = float(tool[-1][0]) + 1.0
    out = [lines[0], *(",".join([r[0], "", "", *r[3:]]) for r in tool),
           *(",".join([repr(float(r[0]) + shift), r[1], r[2], *[""] * 6]) for r in obj)]
    p.write_text("\n".join(out) + "\n")


#: case -> (how to make it, words the message must hold: the file first)
CASES: dict[str, tuple[Callable[[Path], object], tuple[str, ...]]] = {
    # duplicate columns: the first no longer silently wins
    "duplicate obj_x": (lambda f: _header(f, "t,obj_x,obj_y,tool_x,tool_y,tool_yaw,q1,q2,q3,obj_x", ",9"),
                        ("demo_00.csv", "row 1, column obj_x", "2 times")),
    "duplicate q3 among extras": (lambda f: _header(f, "t,obj_x,obj_y,tool_x,tool_y,tool_yaw,q1,q2,q3,note,q3",
                                                    ",x,0"), ("demo_00.csv", "column q3")),
    "duplicate t (whitespace)": (lambda f: _header(f, "t,obj_x,obj_y,tool_x,tool_y,tool_yaw,q1,q2,q3, t ", ",0"),
                                 ("demo_00.csv", "column t")),
    # a tool that is not the recorded one
    "tool slope (a_t)": (lambda f: edit_meta(f, lambda m: m.update(tool="slope")), ("meta.yaml", "field tool")),
    "tool slope and its a_t": (lambda f: edit_meta(f, lambda m: (m.update(tool="slope"),
                                                                 m["platform"].update(a_t=0.028))),
                               ("demo_00.csv", "forward kinematics")),
    "tool i_shape": (lambda f: edit_meta(f, lambda m: m.update(tool="i_shape")), ("meta.yaml", "field tool",
                                                                                   "i_shape", "deep")),
    "tool t_shape": (lambda f: edit_meta(f, lambda m: m.update(tool="t_shape")), ("meta.yaml", "field tool")),
    "tool l_shape": (lambda f: edit_meta(f, lambda m: m.update(tool="l_shape")), ("meta.yaml", "field tool")),
    "custom slope outline, finger a_t": (lambda f: custom_tool(f, "slope", "myslope", a_t=0.026),
                                         ("meta.yaml", "field tool", "myslope.yaml")),
    "custom finger 4 mm forward": (lambda f: custom_tool(f, "finger", "longer", dy=0.004),
                                   ("meta.yaml", "field tool", "longer.yaml")),
    "custom finger 3 mm to the left": (lambda f: custom_tool(f, "finger", "shifted", dx=-0.003),
                                       ("meta.yaml", "field tool", "shifted.yaml")),
    "custom finger 30% smaller": (lambda f: custom_tool(f, "finger", "smaller", shrink=0.7),
                                  ("meta.yaml", "field tool", "smaller.yaml", "while it moves")),
    # units that are not SI
    "positions in mm": (lambda f: [scale(f, (1, 2, 3, 4), 1e3, n) for n in ("demo_00.csv", "demo_01.csv")],
                        ("demo_00.csv", "row 2, columns tool_x, tool_y", "millimetres")),
    "object in mm": (lambda f: scale(f, (1, 2), 1e3), ("demo_00.csv", "columns obj_x, obj_y")),
    "object in cm": (lambda f: scale(f, (1, 2), 1e2), ("demo_00.csv", "columns obj_x, obj_y")),
    "tool in mm": (lambda f: scale(f, (3, 4), 1e3, "demo_01.csv"), ("demo_01.csv", "columns tool_x, tool_y")),
    "joints in degrees": (lambda f: scale(f, (6, 7, 8), DEG), ("demo_00.csv", "column q1", "degrees")),
    "q3 in degrees": (lambda f: scale(f, (8,), DEG), ("demo_00.csv", "column q3")),
    "yaw in degrees": (lambda f: scale(f, (5,), DEG), ("demo_00.csv", "tool_yaw", "forward kinematics")),
    "times in ms": (lambda f: scale(f, (0,), 1e3), ("demo_00.csv", "column t", "rates")),
    "object and tool on other clocks": (_disjoint_streams, ("demo_00.csv", "column t", "same time")),
    "base_xy not the recording's": (lambda f: edit_meta(f, lambda m: m["platform"].update(base_xy=[0.03, 0.0])),
                                    ("demo_00.csv", "forward kinematics")),
    "base_yaw not the recording's": (lambda f: edit_meta(f, lambda m: m["platform"].update(base_yaw=1.4)),
                                     ("demo_00.csv", "forward kinematics")),
    "a_t not the tool's": (lambda f: edit_meta(f, lambda m: m["platform"].update(a_t=0.04)),
                           ("meta.yaml", "field tool", "a_t")),
    # non-finite and unbounded meta fields
    "table_height .inf": (lambda f: replace_meta(f, "table_height: 0.0", "table_height: .inf"),
                          ("meta.yaml", "field platform.table_height", "finite")),
    "base_xy .inf": (lambda f: replace_meta(f, "  - 0.0\n  - 0.0", "  - .inf\n  - 0.0"),
                     ("meta.yaml", "field platform.base_xy.0", "finite")),
    "base_yaw -.inf": (lambda f: replace_meta(f, "base_yaw: 1.5707963267948966", "base_yaw: -.inf"),
                       ("meta.yaml", "field platform.base_yaw")),
    "a_t .nan": (lambda f: replace_meta(f, "a_t: 0.026", "a_t: .nan"), ("meta.yaml", "field platform.a_t")),
    "base_xy 1e6 m": (lambda f: replace_meta(f, "  - 0.0\n  - 0.0", "  - 1.0e+6\n  - 0.0"),
                      ("meta.yaml", "field platform.base_xy")),
    "object_radius .inf": (lambda f: replace_meta(f, "object_radius: 0.0175", "object_radius: .inf"),
                           ("meta.yaml", "field object_radius", "finite")),
    "object_radius in mm": (lambda f: replace_meta(f, "object_radius: 0.0175", "object_radius: 17.5"),
                            ("meta.yaml", "field object_radius")),
    "object_radius true": (lambda f: replace_meta(f, "object_radius: 0.0175", "object_radius: true"),
                           ("meta.yaml", "field object_radius", "boolean")),
    "tool_hz .nan": (lambda f: replace_meta(f, "tool_hz: 100.0", "tool_hz: .nan"), ("meta.yaml", "rates.tool_hz")),
    "object_hz 1e12": (lambda f: replace_meta(f, "object_hz: 30.0", "object_hz: 1.0e+12"),
                       ("meta.yaml", "rates.object_hz")),
    "demonstrations outside the folder": (lambda f: edit_meta(f, lambda m: m.update(demonstrations=["../x.csv"])),
                                          ("meta.yaml", "field demonstrations", "inside")),
    "demonstration named twice": (lambda f: edit_meta(f, lambda m: m.update(demonstrations=["demo_00.csv"] * 2)),
                                  ("meta.yaml", "field demonstrations", "twice")),
    # truth.yaml
    "truth a list": (lambda f: (f / "truth.yaml").write_text("- demo_00\n- demo_01\n"), ("truth.yaml", "mapping")),
    "truth a number": (lambda f: (f / "truth.yaml").write_text("42\n"), ("truth.yaml", "mapping")),
    "truth bad YAML": (lambda f: (f / "truth.yaml").write_text("demo_00: {pushes: [\n"), ("truth.yaml", "line")),
    "truth push time a word": (lambda f: (f / "truth.yaml").write_text(
        "demo_00:\n  pushes:\n  - {face: upper, t_start: soon, t_end: 2.0}\n"),
        ("truth.yaml", "demo_00.pushes.0.t_start")),
    "truth demo a list": (lambda f: (f / "truth.yaml").write_text("demo_01: [1, 2]\n"), ("truth.yaml", "demo_01")),
    # bytes
    "CSV in UTF-16": (lambda f: (f / "demo_00.csv").write_bytes((f / "demo_00.csv").read_text().encode("utf-16")),
                      ("demo_00.csv", "UTF-8")),
    "CSV in Latin-1": (lambda f: (f / "demo_01.csv").write_bytes(
        (f / "demo_01.csv").read_text().replace("q3", "q3,d\xe9but", 1).encode("latin-1")), ("demo_01.csv", "UTF-8")),
    "CSV binary": (lambda f: (f / "demo_00.csv").write_bytes(bytes(range(256)) * 64), ("demo_00.csv",)),
    "CSV with NUL bytes": (lambda f: (f / "demo_00.csv").write_text("t,obj_x\x00\n1,2\n"), ("demo_00.csv", "NUL")),
    "CSV of 100 MB": (lambda f: (f / "demo_00.csv").open("a").truncate(100 * 2**20),
                      ("demo_00.csv", "<file>", "at most 32 MB")),
}


@pytest.fixture
def copy(tmp_path: Path) -> Path:
    return copy_dataset(tmp_path / "ds")


def _load_and_segment(folder: Path) -> None:
    ds = load_dataset(folder)
    tool = ds.tool()
    for d in ds.demonstrations:
        segment(d, tool, radius=float(ds.meta.object_radius))


def test_the_unchanged_copy_loads_and_segments(copy: Path) -> None:
    _load_and_segment(copy)
    assert main(["segment", str(copy)]) == 0


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_lying_dataset_is_refused_naming_the_file_and_the_field(copy: Path, name: str) -> None:
    make, words = CASES[name]
    make(copy)
    start = time.perf_counter()
    with pytest.raises(DatasetError) as err:
        _load_and_segment(copy)
    assert time.perf_counter() - start < 10
    msg = str(err.value)
    assert "\n" not in msg and len(msg) < 600, msg
    assert str(copy) in msg, msg  # the file, with its folder
    for w in words:
        assert w in msg, msg


def test_the_row_cap_streams_and_stops_with_a_message(copy: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(dataset_module, "MAX_ROWS", 1000)
    with pytest.raises(DatasetError, match=r"demo_00.csv: row 1002: expected at most 1000 data rows"):
        load_dataset(copy)


@pytest.mark.serial  # refused within 10 s, reading 500,000 rows
def test_a_long_csv_is_read_into_arrays_not_row_lists(copy: Path) -> None:
    """The loader streams: a 30 MB recording (over 500,000 rows) is refused at the row cap within
    seconds, and a long valid one holds its samples as float arrays."""
    p = copy / "demo_00.csv"
    row = ",,,0.034979,0.086708,-0.4906,-0.4906,0.1306,1.5816\n"
    with p.open("w") as fh:
        fh.write("t,obj_x,obj_y,tool_x,tool_y,tool_yaw,q1,q2,q3\n")
        fh.writelines(f"{0.01 * i:.2f}{row}" for i in range(520_000))
    start = time.perf_counter()
    with pytest.raises(DatasetError, match="at most 500000 data rows"):
        load_dataset(copy)
    assert time.perf_counter() - start < 10


@pytest.mark.parametrize("content, words", [
    ({"demo_00": [["a", 0.1]]}, ("demo_00[0][0]", "a finite number", "'a'")),
    ({"demo_00": [[0.1, 0.2, 0.3]]}, ("demo_00[0]", "a point [x, y]")),
    ({"demo_00": [[True, 0.1]]}, ("demo_00[0][0]", "True")),
    ({"demo_00": [[None, 0.1]]}, ("demo_00[0][0]",)),
    ({"demo_00": "corner"}, ("demo_00", "a list of [x, y] points")),
    ({"demo_99": [[0.0, 0.1]]}, ("demo_99", "a demonstration's name")),
    ([[0.0, 0.1]], ("a JSON object",)),
    ("[[1, 2", ("a JSON file",)),
])
def test_fixed_points_file_errors_exit_2_naming_the_file_and_entry(copy: Path, capsys, content, words) -> None:
    f = copy / "fixed.json"
    f.write_text(content if isinstance(content, str) else json.dumps(content))
    assert main(["segment", str(copy), "--fixed-points", str(f)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "--fixed-points" in err and str(f) in err, err
    for w in words:
        assert w in err, err
    with pytest.raises(InputError):
        load_fixed_points(f, ["demo_00", "demo_01"])


def test_valid_fixed_points_are_used(copy: Path) -> None:
    f = copy / "fixed.json"
    f.write_text(json.dumps({"demo_00": [[0.06, 0.16]]}))
    assert load_fixed_points(f, ["demo_00", "demo_01"])["demo_00"].tolist() == [[0.06, 0.16]]


@pytest.mark.parametrize("name", ["positions in mm", "tool i_shape", "duplicate obj_x", "truth a list"])
def test_segment_and_learn_exit_2_with_one_line(copy: Path, tmp_path: Path, capsys, name: str) -> None:
    CASES[name][0](copy)
    for argv in (["segment", str(copy)], ["learn", str(copy), "-o", str(tmp_path / "skills.json")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "Traceback" not in err and err.count("\n") == 1 and str(copy) in err, err
    assert not (tmp_path / "skills.json").exists()
