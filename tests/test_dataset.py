"""The dataset format: loader errors name the file, row and column; write/read round trip."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from tooltransfer.problems.dataset import (
    COLUMNS,
    MIN_SAMPLES,
    DatasetError,
    Demonstration,
    Meta,
    PlatformMeta,
    Rates,
    load_dataset,
    write_dataset,
    write_demonstration,
)

DATA = Path(__file__).resolve().parents[1] / "problems" / "data" / "finger_demos"
LIBRARY = Path(__file__).resolve().parents[1] / "tools" / "library"


def _demo(name: str, n_obj: int = 15, n_tool: int = 40, seed: int = 0) -> Demonstration:
    """A small demonstration: camera at 30 Hz, encoders at 100 Hz (own time bases)."""
    rng = np.random.default_rng(seed)
    t_o = 0.033 * np.arange(1, n_obj + 1)
    t_t = 0.01 * np.arange(1, n_tool + 1)
    return Demonstration(name, t_o, rng.normal([0.04, 0.12], 0.001, (n_obj, 2)), t_t,
                         rng.normal([0.035, 0.09, -0.4], 0.001, (n_tool, 3)), rng.normal(0.5, 0.1, (n_tool, 3)))


def _meta(names: list[str], tool: str = "finger") -> Meta:
    return Meta(tool=tool, object_radius=0.0175, rates=Rates(object_hz=30.0, tool_hz=100.0),
                platform=PlatformMeta(a_t=0.026), demonstrations=names)


@pytest.fixture
def small(tmp_path: Path) -> Path:
    """A valid two-demonstration dataset in a temporary folder."""
    return write_dataset(tmp_path / "ds", _meta(["a.csv", "b.csv"]), [_demo("a"), _demo("b", seed=1)])


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines()


def _row_of(path: Path, predicate) -> int:
    """1-based row number (header = row 1) of the first data row satisfying ``predicate(cells)``."""
    for i, line in enumerate(_lines(path)[1:], start=2):
        if predicate(line.split(",")):
            return i
    raise AssertionError("no such row")


def _edit(path: Path, row: int, column: str, value: str) -> None:
    lines = _lines(path)
    cells = lines[row - 1].split(",")
    cells[COLUMNS.index(column)] = value
    lines[row - 1] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")


def _raises(folder: Path, *words: str) -> str:
    with pytest.raises(DatasetError) as err:
        load_dataset(folder)
    msg = str(err.value)
    for w in words:
        assert w in msg, msg
    return msg


def test_valid_small_dataset_loads_with_separate_time_bases(small: Path) -> None:
    ds = load_dataset(small)
    a = ds.demonstrations[0]
    assert a.t_object.shape == (15,) and a.object_xy.shape == (15, 2)
    assert a.t_tool.shape == (40,) and a.tool_pose.shape == (40, 3) and a.joints.shape == (40, 3)
    assert ds.tool().name == "finger"
    assert ds.truth is None


def test_missing_column_names_file_row_and_column(small: Path) -> None:
    f = small / "a.csv"
    f.write_text(f.read_text().replace("tool_yaw", "heading", 1))
    _raises(small, str(f), "row 1", "missing tool_yaw")


def test_nan_names_file_row_and_column(small: Path) -> None:
    f = small / "b.csv"
    row = _row_of(f, lambda c: c[1] != "")
    _edit(f, row, "obj_x", "nan")
    _raises(small, str(f), f"row {row}, column obj_x", "finite")


def test_non_number_names_file_row_and_column(small: Path) -> None:
    f = small / "a.csv"
    row = _row_of(f, lambda c: c[7] != "")
    _edit(f, row, "q2", "1;5")
    _raises(small, str(f), f"row {row}, column q2", "a number")


def test_time_going_back_names_file_row_and_column(small: Path) -> None:
    f = small / "a.csv"
    lines = _lines(f)
    lines[9], lines[10] = lines[10], lines[9]  # rows 10 and 11 swapped
    f.write_text("\n".join(lines) + "\n")
    _raises(small, str(f), "row 11, column t", "a time after the previous row's")


def test_repeated_time_is_not_increasing(small: Path) -> None:
    f = small / "a.csv"
    lines = _lines(f)
    lines[5] = lines[4].split(",")[0] + "," + ",".join(lines[5].split(",")[1:])
    f.write_text("\n".join(lines) + "\n")
    _raises(small, str(f), "row 6, column t")


def test_too_few_samples_names_file_and_columns(tmp_path: Path) -> None:
    folder = write_dataset(tmp_path / "ds", _meta(["a.csv"]), [_demo("a", n_obj=MIN_SAMPLES - 1)])
    _raises(folder, str(folder / "a.csv"), "columns obj_x, obj_y", f"at least {MIN_SAMPLES} object samples")
    folder = write_dataset(tmp_path / "ds2", _meta(["a.csv"]), [_demo("a", n_tool=3)])
    _raises(folder, str(folder / "a.csv"), "columns tool_x", f"at least {MIN_SAMPLES} tool samples", "got 3")


def test_unknown_tool_names_meta_field(small: Path) -> None:
    m = small / "meta.yaml"
    m.write_text(m.read_text().replace("tool: finger", "tool: hammer"))
    _raises(small, str(m), "field tool", "finger", "'hammer'")


def test_half_filled_stream_names_the_empty_cell(small: Path) -> None:
    f = small / "a.csv"
    row = _row_of(f, lambda c: c[3] != "")
    _edit(f, row, "q3", "")
    _raises(small, str(f), f"row {row}, column q3", "its stream's other cells are filled")


def test_missing_time_and_time_only_rows(small: Path) -> None:
    f = small / "a.csv"
    original = f.read_text()
    _edit(f, 4, "t", "")
    _raises(small, str(f), "row 4, column t", "a time")
    f.write_text(original)
    lines = _lines(f)
    lines[3] = lines[3].split(",")[0] + "," * 8
    f.write_text("\n".join(lines) + "\n")
    _raises(small, str(f), "row 4", "object or tool values")


def test_meta_schema_errors_name_the_field(small: Path) -> None:
    m = small / "meta.yaml"
    text = m.read_text()
    m.write_text(text.replace("object_radius: 0.0175", "object_radius: -0.0175"))
    _raises(small, str(m), "field object_radius", "greater than 0")
    m.write_text(text.replace("  tool_hz: 100.0", "  tool_hz: fast"))
    _raises(small, str(m), "field rates.tool_hz")
    m.write_text(text.replace("units: SI", "units: mm"))
    _raises(small, str(m), "field units")
    m.write_text(text + "colour: blue\n")
    _raises(small, str(m), "field colour", "Extra inputs")
    m.write_text(text.replace("tool: finger", "tool: [finger"))
    _raises(small, str(m), "line", "column", "valid YAML")


def test_missing_csv_is_named(small: Path) -> None:
    (small / "b.csv").unlink()
    _raises(small, str(small / "b.csv"), "a readable CSV file")


def test_tool_given_as_a_yaml_path(small: Path) -> None:
    shutil.copy(LIBRARY / "finger.yaml", small / "my_tool.yaml")
    m = small / "meta.yaml"
    m.write_text(m.read_text().replace("tool: finger", "tool: my_tool.yaml"))
    assert load_dataset(small).tool().face_names == ("upper", "left")
    (small / "my_tool.yaml").write_text("name: broken\n")
    _raises(small, str(small / "my_tool.yaml"), "a valid tool file")


def test_writer_puts_simultaneous_samples_on_one_row(tmp_path: Path) -> None:
    d = _demo("a", n_obj=12, n_tool=12)
    d = Demonstration("a", d.t_tool.copy(), d.object_xy, d.t_tool, d.tool_pose, d.joints)  # same instants
    write_demonstration(tmp_path / "a.csv", d)
    lines = _lines(tmp_path / "a.csv")
    assert len(lines) == 13 and all("" not in line.split(",") for line in lines[1:])


def test_round_trip_of_the_committed_dataset(tmp_path: Path) -> None:
    ds = load_dataset(DATA)
    again = load_dataset(write_dataset(tmp_path / "copy", ds.meta, list(ds.demonstrations), ds.truth))
    assert again.meta == ds.meta and again.truth == ds.truth
    for a, b in zip(ds.demonstrations, again.demonstrations, strict=True):
        assert a.name == b.name
        for field in ("t_object", "object_xy", "t_tool", "tool_pose", "joints"):
            x, y = getattr(a, field), getattr(b, field)
            assert x.shape == y.shape
            np.testing.assert_array_equal(x, y)  # 6 decimals written, the same 6 decimals read
    for p in DATA.glob("*.csv"):
        assert (tmp_path / "copy" / p.name).read_text() == p.read_text()
