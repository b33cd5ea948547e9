"""Demonstration datasets: a folder with ``meta.yaml`` and one CSV per demonstration.

Format ``tooltransfer.dataset/1`` (documented in the README so users can bring real recordings):

* ``meta.yaml``: ``format``, ``units`` (SI: m, rad, s), ``frame`` (world frame of DESIGN section 2),
  ``tool`` (a library name or a path to a tool YAML, relative to the folder), ``object_radius``
  [m], ``rates`` (``object_hz``, ``tool_hz``), ``platform`` (``a_t``, ``base_xy``, ``base_yaw``,
  ``table_height``), ``demonstrations`` (the CSV file names, in order), and optional
  ``scene``/``generator`` blocks describing how the data were made.
* ``<demo>.csv``: a header ``t,obj_x,obj_y,tool_x,tool_y,tool_yaw,q1,q2,q3`` and rows in increasing
  time [s]; the object columns (a camera) and the tool and joint columns (encoders) have their
  own time bases: a row leaves the other stream's cells empty.
* optional ``truth.yaml``: for generated data, the operator's ground truth (pushes and switches).

:func:`load_dataset` checks everything and names the file, row and column of any problem.
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

FORMAT = "tooltransfer.dataset/1"
COLUMNS = ("t", "obj_x", "obj_y", "tool_x", "tool_y", "tool_yaw", "q1", "q2", "q3")
OBJECT_COLUMNS, TOOL_COLUMNS = COLUMNS[1:3], COLUMNS[3:]
MIN_SAMPLES = 10


class DatasetError(InputError):
    """A dataset file is invalid; names the file, and the row and column where it applies."""

    def __init__(self, path: str, where: str, expected: str, got: object | None = None) -> None:
        self.path = path
        super().__init__(f"{path}: {where}", expected, got)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Rates(_Model):
    object_hz: float = Field(gt=0, description="camera rate [Hz]")
    tool_hz: float = Field(gt=0, description="encoder rate [Hz]")


class PlatformMeta(_Model):
    a_t: float = Field(gt=0, description="[m]")
    base_xy: tuple[float, float] = (0.0, 0.0)
    base_yaw: float = float(np.pi / 2)
    table_height: float = 0.0


class Meta(_Model):
    """``meta.yaml``."""

    format: Literal["tooltransfer.dataset/1"] = FORMAT
    units: Literal["SI"] = "SI"
    frame: str = "world: table plane, origin under the Omni's joint-1 axis, x right, y forward, z up"
    tool: str
    object_radius: float = Field(gt=0, description="[m]")
    rates: Rates
    platform: PlatformMeta
    demonstrations: list[str] = Field(min_length=1)
    scene: dict[str, Any] | None = None
    generator: dict[str, Any] | None = None


@dataclass(frozen=True)
class Demonstration:
    """One recorded demonstration: object track ``t_object`` (M,), ``object_xy`` (M, 2); tool track
    ``t_tool`` (N,), ``tool_pose`` (N, 3) (x, y [m], yaw [rad]), ``joints`` (N, 3) [rad]."""

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


def write_demonstration(path: Path, demo: Demonstration) -> None:
    """Write one demonstration's CSV (6 decimals: micrometres and microradians)."""
    rows: list[tuple[float, list[str]]] = []
    for t, (x, y) in zip(demo.t_object, demo.object_xy, strict=True):
        rows.append((t, [f"{x:.6f}", f"{y:.6f}"] + [""] * 6))
    for t, pose, q in zip(demo.t_tool, demo.tool_pose, demo.joints, strict=True):
        rows.append((t, ["", ""] + [f"{v:.6f}" for v in (*pose, *q)]))
    rows.sort(key=lambda r: r[0])
    out: list[list[str]] = []
    for t, cells in rows:
        stamp = f"{t:.6f}"
        if out and out[-1][0] == stamp:  # both streams at one instant: one row
            out[-1] = [stamp, *(a or b for a, b in zip(out[-1][1:], cells, strict=True))]
        else:
            out.append([stamp, *cells])
    with path.open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(COLUMNS)
        w.writerows(out)


def write_dataset(folder: str | Path, meta: Meta, demos: list[Demonstration], truth: dict | None = None) -> Path:
    """Write ``meta.yaml``, the CSVs (named as in ``meta.demonstrations``) and ``truth.yaml``."""
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
    if header is None:
        raise DatasetError(where, "row 1", f"a header with columns {', '.join(COLUMNS)}", "an empty file")
    header = [h.strip() for h in header]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise DatasetError(where, "row 1", f"columns {', '.join(COLUMNS)}", f"missing {', '.join(missing)}")
    idx = {c: header.index(c) for c in COLUMNS}
    t_o, o, t_t, k = [], [], [], []
    for r, row in enumerate(rows, start=2):
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
        obj = [cell(c) for c in OBJECT_COLUMNS]
        tool = [cell(c) for c in TOOL_COLUMNS]
        for group, cols in ((obj, OBJECT_COLUMNS), (tool, TOOL_COLUMNS)):
            if any(v is None for v in group) and any(v is not None for v in group):
                col = cols[[v is None for v in group].index(True)]
                raise DatasetError(where, f"row {r}, column {col}", "a value (its stream's other cells are filled)")
        if obj[0] is not None:
            if t_o and t <= t_o[-1][0]:
                raise DatasetError(where, f"row {r}, column t", f"object times increasing (after {t_o[-1][0]})", t)
            t_o.append((t, r))
            o.append(obj)
        if tool[0] is not None:
            if t_t and t <= t_t[-1][0]:
                raise DatasetError(where, f"row {r}, column t", f"tool times increasing (after {t_t[-1][0]})", t)
            t_t.append((t, r))
            k.append(tool)
    for n, what in ((len(t_o), "object"), (len(t_t), "tool")):
        if n < MIN_SAMPLES:
            raise DatasetError(where, f"{what} columns", f"at least {MIN_SAMPLES} samples", n)
    ka = np.array(k, dtype=np.float64)
    return Demonstration(path.stem, np.array([a for a, _ in t_o]), np.array(o, dtype=np.float64),
                         np.array([a for a, _ in t_t]), ka[:, :3], ka[:, 3:])


def load_dataset(folder: str | Path) -> Dataset:
    """Load and check a dataset folder."""
    root = Path(folder)
    meta_path = root / "meta.yaml"
    try:
        raw = yaml.safe_load(meta_path.read_text())
    except OSError as exc:
        raise DatasetError(str(meta_path), "<file>", "a readable meta.yaml", exc.strerror) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "<file>"
        raise DatasetError(str(meta_path), where, "valid YAML", getattr(exc, "problem", str(exc))) from None
    try:
        meta = Meta.model_validate(raw)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = ".".join(str(p) for p in err["loc"]) or "<root>"
        raise DatasetError(str(meta_path), loc, err["msg"], err.get("input")) from None
    from tools.library import library_names, read_tool_file

    if meta.tool not in library_names():
        tool_path = root / meta.tool
        if not tool_path.is_file():
            raise DatasetError(str(meta_path), "tool", f"a library tool ({', '.join(library_names())}) or a tool "
                               "YAML path relative to the dataset", repr(meta.tool))
        read_tool_file(tool_path)
    demos = tuple(_read_csv(root / name) for name in meta.demonstrations)
    truth_path = root / "truth.yaml"
    truth = yaml.safe_load(truth_path.read_text()) if truth_path.is_file() else None
    return Dataset(root, meta, demos, truth)
