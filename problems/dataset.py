"""Demonstration datasets: a folder with ``meta.yaml`` and one CSV per demonstration.

Format ``tooltransfer.dataset/1`` (documented in the README so users can bring real recordings):

* ``meta.yaml``: ``format``, ``units`` (SI: m, rad, s), ``frame`` (the world frame of DESIGN
  section 2), ``tool`` (a library name or a path to a tool YAML, relative to the folder),
  ``object_radius`` [m], ``rates`` (``object_hz``, ``tool_hz``: nominal, for information),
  ``platform`` (``a_t``, ``base_xy``, ``base_yaw``, ``table_height``), ``demonstrations`` (the CSV
  file names, in order), and optional ``scene`` / ``generator`` blocks (free-form: how the data
  were made and in which task).
* ``<demo>.csv``: a header naming at least ``t,obj_x,obj_y,tool_x,tool_y,tool_yaw,q1,q2,q3`` (any
  order; other columns are ignored) and rows in strictly increasing time ``t`` [s]. The object
  columns (a camera) and the tool and joint columns (encoders) have their own time bases: a row
  fills one stream's cells and leaves the other's empty, or fills both when both streams have a
  sample at that instant. Each stream needs at least ``MIN_SAMPLES`` samples.
* optional ``truth.yaml``: for generated data, the operator's ground truth (pushes, switches).

:func:`load_dataset` checks everything and names the file, and the row and column, of any problem
(rows count from 1 at the header, as a spreadsheet shows them).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import yaml
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from dmp.errors import InputError
from tools.model import Tool

FORMAT = "tooltransfer.dataset/1"
COLUMNS = ("t", "obj_x", "obj_y", "tool_x", "tool_y", "tool_yaw", "q1", "q2", "q3")
OBJECT_COLUMNS, TOOL_COLUMNS = COLUMNS[1:3], COLUMNS[3:]
MIN_SAMPLES = 10
"""Fewest samples per stream (object, tool) in one demonstration."""


class DatasetError(InputError):
    """A dataset file is invalid; names the file, and the row and column where it applies."""

    def __init__(self, path: str, where: str, expected: str, got: object | None = None) -> None:
        self.path = path
        super().__init__(f"{path}: {where}", expected, got)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Rates(_Model):
    """Nominal sampling rates [Hz]."""

    object_hz: float = Field(gt=0, description="object track (camera) rate [Hz]")
    tool_hz: float = Field(gt=0, description="tool and joint track (encoders) rate [Hz]")


class PlatformMeta(_Model):
    """The Omni the demonstrations were recorded on (DESIGN section 7)."""

    a_t: float = Field(gt=0, description="DH tool length a_t [m]")
    base_xy: tuple[float, float] = Field((0.0, 0.0), description="world position of the joint-1 axis [m]")
    base_yaw: float = Field(float(np.pi / 2), description="world direction of the arm at q1 = 0 [rad]")
    table_height: float = Field(0.0, description="table height in the Omni base frame [m]")


class Meta(_Model):
    """``meta.yaml``."""

    format: Literal["tooltransfer.dataset/1"] = FORMAT
    units: Literal["SI"] = Field("SI", description="metres, radians, seconds")
    frame: str = "world: table plane, origin under the Omni's joint-1 axis, x right, y forward, z up"
    tool: str = Field(min_length=1, description="library tool name, or tool YAML path relative to the folder")
    object_radius: float = Field(gt=0, description="radius of the disc object [m]")
    rates: Rates
    platform: PlatformMeta
    demonstrations: list[str] = Field(min_length=1, description="CSV file names, in order")
    scene: dict[str, Any] | None = None
    generator: dict[str, Any] | None = None


@dataclass(frozen=True)
class Demonstration:
    """One recorded demonstration.

    Attributes:
        name: the CSV file's stem.
        t_object (M,) [s], object_xy (M, 2) [m]: the object track.
        t_tool (N,) [s], tool_pose (N, 3) (x, y [m], yaw [rad]), joints (N, 3) [rad]: the tool track.
    """

    name: str
    t_object: NDArray[np.float64]
    object_xy: NDArray[np.float64]
    t_tool: NDArray[np.float64]
    tool_pose: NDArray[np.float64]
    joints: NDArray[np.float64]


@dataclass(frozen=True)
class Dataset:
    """A loaded dataset: its folder, metadata, demonstrations and (generated data) ground truth."""

    folder: Path
    meta: Meta
    demonstrations: tuple[Demonstration, ...]
    truth: dict[str, Any] | None = None

    def tool(self) -> Tool:
        """The demonstration tool (a library tool, or the tool YAML next to the data)."""
        from tools.library import library_names, load_tool

        return load_tool(self.meta.tool if self.meta.tool in library_names() else self.folder / self.meta.tool)


def _fmt(v: float) -> str:
    """Six decimals (micrometres, microradians, microseconds) without trailing zeros."""
    s = f"{v:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def write_demonstration(path: str | Path, demo: Demonstration) -> None:
    """Write one demonstration's CSV; both streams' samples merged in time order."""
    rows: dict[str, list[str]] = {}
    for t, (x, y) in zip(demo.t_object, demo.object_xy, strict=True):
        rows.setdefault(_fmt(t), [""] * 8)[0:2] = [_fmt(x), _fmt(y)]
    for t, pose, q in zip(demo.t_tool, demo.tool_pose, demo.joints, strict=True):
        rows.setdefault(_fmt(t), [""] * 8)[2:8] = [_fmt(v) for v in (*pose, *q)]
    with Path(path).open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(COLUMNS)
        w.writerows([stamp, *cells] for stamp, cells in sorted(rows.items(), key=lambda r: float(r[0])))


def write_dataset(folder: str | Path, meta: Meta, demos: list[Demonstration], truth: dict | None = None) -> Path:
    """Write ``meta.yaml``, the CSVs (named as in ``meta.demonstrations``) and ``truth.yaml``;
    returns the folder."""
    if len(demos) != len(meta.demonstrations):
        raise InputError("demos", f"{len(meta.demonstrations)} demonstrations (as meta.demonstrations)", len(demos))
    root = Path(folder)
    root.mkdir(parents=True, exist_ok=True)
    (root / "meta.yaml").write_text(yaml.safe_dump(meta.model_dump(mode="json"), sort_keys=False))
    for name, demo in zip(meta.demonstrations, demos, strict=True):
        write_demonstration(root / name, demo)
    if truth is not None:
        (root / "truth.yaml").write_text(yaml.safe_dump(truth, sort_keys=False))
    return root


def _read_csv(path: Path) -> Demonstration:
    where = str(path)
    try:
        with path.open(newline="") as fh:
            reader = csv.reader(fh)
            header = next(reader, None)
            rows = list(reader)
    except OSError as exc:
        raise DatasetError(where, "<file>", "a readable CSV file", exc.strerror) from None
    except csv.Error as exc:
        raise DatasetError(where, "<file>", "a CSV file", str(exc)) from None
    if header is None:
        raise DatasetError(where, "row 1", f"a header with columns {', '.join(COLUMNS)}", "an empty file")
    header = [h.strip() for h in header]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise DatasetError(where, "row 1", f"columns {', '.join(COLUMNS)}", f"missing {', '.join(missing)}")
    idx = {c: header.index(c) for c in COLUMNS}
    t_o: list[float] = []
    t_t: list[float] = []
    o: list[list[float]] = []
    k: list[list[float]] = []
    last: float | None = None
    for r, row in enumerate(rows, start=2):
        if not any(cell.strip() for cell in row):
            continue  # a blank line

        def cell(col: str, row: list[str] = row, r: int = r) -> float | None:
            raw = row[idx[col]].strip() if idx[col] < len(row) else ""
            if raw == "":
                return None
            try:
                v = float(raw)
            except ValueError:
                raise DatasetError(where, f"row {r}, column {col}", "a number", repr(raw)) from None
            if not math.isfinite(v):
                raise DatasetError(where, f"row {r}, column {col}", "a finite number", raw)
            return v

        t = cell("t")
        if t is None:
            raise DatasetError(where, f"row {r}, column t", "a time [s]", "an empty cell")
        if last is not None and t <= last:
            raise DatasetError(where, f"row {r}, column t", f"a time after the previous row's {last}", t)
        last = t
        obj = [cell(c) for c in OBJECT_COLUMNS]
        tool = [cell(c) for c in TOOL_COLUMNS]
        for group, cols in ((obj, OBJECT_COLUMNS), (tool, TOOL_COLUMNS)):
            if any(v is None for v in group) and any(v is not None for v in group):
                col = cols[[v is None for v in group].index(True)]
                raise DatasetError(where, f"row {r}, column {col}", "a value (its stream's other cells are filled)",
                                   "an empty cell")
        if obj[0] is None and tool[0] is None:
            raise DatasetError(where, f"row {r}", "object or tool values next to the time", "only a time")
        if obj[0] is not None:
            t_o.append(t)
            o.append(obj)  # type: ignore[arg-type]
        if tool[0] is not None:
            t_t.append(t)
            k.append(tool)  # type: ignore[arg-type]
    for n, what, cols in ((len(t_o), "object", OBJECT_COLUMNS), (len(t_t), "tool", TOOL_COLUMNS)):
        if n < MIN_SAMPLES:
            raise DatasetError(where, f"columns {', '.join(cols)}", f"at least {MIN_SAMPLES} {what} samples", n)
    ka = np.array(k, dtype=np.float64)
    return Demonstration(path.stem, np.array(t_o), np.array(o, dtype=np.float64), np.array(t_t), ka[:, :3], ka[:, 3:])


def load_meta(folder: str | Path) -> Meta:
    """Read and validate ``meta.yaml`` of a dataset folder (errors name the field path)."""
    from problems.yaml_file import read_yaml

    meta_path = Path(folder) / "meta.yaml"
    raw = read_yaml(meta_path, DatasetError, "meta.yaml")
    try:
        return Meta.model_validate(raw)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = ".".join(str(p) for p in err["loc"]) or "<root>"
        raise DatasetError(str(meta_path), f"field {loc}", err["msg"], err.get("input")) from None


def load_dataset(folder: str | Path) -> Dataset:
    """Load and check a dataset folder (see the module docstring for the format).

    Raises:
        DatasetError: naming the file (and row and column, or field) of the first problem.
    """
    root = Path(folder)
    meta = load_meta(root)
    from tools.errors import ToolSpecError
    from tools.library import library_names, read_tool_file

    if meta.tool not in library_names():
        tool_path = root / meta.tool
        if not tool_path.is_file():
            raise DatasetError(str(root / "meta.yaml"), "field tool", f"a library tool ({', '.join(library_names())}) "
                               "or a tool YAML path relative to the dataset", repr(meta.tool))
        try:
            read_tool_file(tool_path)
        except ToolSpecError as exc:
            raise DatasetError(str(tool_path), "<file>", "a valid tool file", str(exc)) from None
    demos = tuple(_read_csv(root / name) for name in meta.demonstrations)
    truth_path = root / "truth.yaml"
    truth = yaml.safe_load(truth_path.read_text()) if truth_path.is_file() else None
    return Dataset(root, meta, demos, truth)
