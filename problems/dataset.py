"""Demonstration datasets: a folder with ``meta.yaml`` and one CSV per demonstration.

Format ``tooltransfer.dataset/1`` (documented in the README so users can bring real recordings):

* ``meta.yaml``: ``format``, ``units`` (SI: m, rad, s), ``frame`` (the world frame of docs/design.md
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
(rows count from 1 at the header, as a spreadsheet shows them). Every file is read as data, inside the
folder, links resolved (:mod:`tooltransfer.regular_file`): no message quotes a file from outside it.
"""

from __future__ import annotations

import csv
import io
import math
from array import array
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path, PurePosixPath
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from numpy.typing import NDArray
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, field_validator

from tooltransfer.atomic import write_text
from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool

FORMAT = "tooltransfer.dataset/1"
COLUMNS = ("t", "obj_x", "obj_y", "tool_x", "tool_y", "tool_yaw", "q1", "q2", "q3")
OBJECT_COLUMNS, TOOL_COLUMNS = COLUMNS[1:3], COLUMNS[3:]
MIN_SAMPLES = 10
"""Fewest samples per stream (object, tool) in one demonstration."""
MAX_CSV_BYTES = 32 * 2**20
"""Largest demonstration CSV read [bytes] (about 5 hours of encoders at 100 Hz with the camera)."""
MAX_ROWS = 500_000
"""Most data rows read from one CSV (the file is streamed; reading stops with an error past this)."""
MAX_DEMONSTRATIONS = 1000
RATE_FACTOR = 4.0
"""A stream's measured rate (median time step) must lie within this factor of its ``rates`` entry."""
REACH_SLACK = 0.02
"""Plausibility [m]: tool positions lie within the Omni's reach region grown by this much, object
positions within it grown by this plus the tool's extent and the object's radius."""
JOINT_SLACK = 0.2
"""Plausibility [rad]: joints lie within the Omni's joint limits widened by this much."""


class DatasetError(InputError):
    """A dataset file is invalid; names the file, and the row and column where it applies."""

    def __init__(self, path: str, where: str, expected: str, got: object | None = None) -> None:
        self.path = path
        super().__init__(f"{path}: {where}", expected, got)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _not_bool(v: Any) -> Any:
    if isinstance(v, bool):
        raise ValueError("a number, not a boolean")
    if isinstance(v, float) and not math.isfinite(v):
        raise ValueError("a finite number")
    return v


Number = Annotated[float, BeforeValidator(_not_bool), Field(allow_inf_nan=False)]
"""A finite number (no boolean, no ``.inf`` or ``.nan``)."""


class Rates(_Model):
    """Nominal sampling rates [Hz] (the measured rates must lie within :data:`RATE_FACTOR` of them)."""

    object_hz: Number = Field(gt=0, le=10_000, description="object track (camera) rate [Hz]")
    tool_hz: Number = Field(gt=0, le=10_000, description="tool and joint track (encoders) rate [Hz]")


class PlatformMeta(_Model):
    """The Omni the demonstrations were recorded on (docs/design.md section 7)."""

    a_t: Number = Field(gt=0, le=0.5, description="DH tool length a_t [m] (the declared tool's a_t)")
    base_xy: tuple[Number, Number] = Field((0.0, 0.0), description="world position of the joint-1 axis [m]")
    base_yaw: Number = Field(float(np.pi / 2), ge=-10, le=10, description="world direction of the arm at q1 = 0 "
                             "[rad]")
    table_height: Number = Field(0.0, ge=-1, le=1, description="table height in the Omni base frame [m]")

    @field_validator("base_xy")
    @classmethod
    def _near(cls, v: tuple[float, float]) -> tuple[float, float]:
        if max(abs(v[0]), abs(v[1])) > 10.0:
            raise ValueError("a position within 10 m of the world origin [m]")
        return v


class Meta(_Model):
    """``meta.yaml``."""

    format: Literal["tooltransfer.dataset/1"] = FORMAT
    units: Literal["SI"] = Field("SI", description="metres, radians, seconds")
    frame: str = "world: table plane, origin under the Omni's joint-1 axis, x right, y forward, z up"
    tool: str = Field(min_length=1, max_length=1000,
                      description="library tool name, or tool YAML path relative to the folder")
    object_radius: Number = Field(gt=0, le=0.2, description="radius of the disc object [m] (at most 0.2 m)")
    rates: Rates
    platform: PlatformMeta
    demonstrations: list[str] = Field(min_length=1, max_length=MAX_DEMONSTRATIONS,
                                      description="CSV file names (inside the folder), in order, each once")
    scene: dict[str, Any] | None = None
    generator: dict[str, Any] | None = None

    @field_validator("demonstrations")
    @classmethod
    def _inside(cls, v: list[str]) -> list[str]:
        seen: set[str] = set()
        for name in v:
            parts = PurePosixPath(name.replace("\\", "/")).parts
            if not name.strip() or name.startswith(("/", "\\")) or ".." in parts or ":" in name:
                raise ValueError(f"CSV file names inside the dataset folder, not {name[:80]!r}")
            if name in seen:
                raise ValueError(f"each CSV file named once, not {name[:80]!r} twice")
            seen.add(name)
        return v


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
    origin: Origin | None = None


@dataclass(frozen=True)
class Origin:
    """Where a loaded demonstration comes from, for the checks that need the dataset around it (the
    segmentation checks the recordings against the declared tool and the platform's kinematics).

    Attributes:
        csv: the CSV file; meta: its ``meta.yaml``; tool: ``meta.tool`` as written.
        platform: ``meta.platform``; object_radius [m].
        object_rows, tool_rows: the CSV row (1 = header) of each object and tool sample.
    """

    csv: str
    meta: str
    tool: str
    platform: PlatformMeta
    object_radius: float
    object_rows: NDArray[np.int64]
    tool_rows: NDArray[np.int64]


@dataclass(frozen=True)
class Dataset:
    """A loaded dataset: its folder, metadata, demonstrations and (generated data) ground truth."""

    folder: Path
    meta: Meta
    demonstrations: tuple[Demonstration, ...]
    truth: dict[str, Any] | None = None

    def tool(self) -> Tool:
        """The demonstration tool (a library tool, or the tool YAML next to the data)."""
        from tooltransfer.tools.library import library_names, load_tool

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
    buf = io.StringIO(newline="")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    w.writerows([stamp, *cells] for stamp, cells in sorted(rows.items(), key=lambda r: float(r[0])))
    write_text(path, buf.getvalue())


def write_dataset(folder: str | Path, meta: Meta, demos: list[Demonstration], truth: dict | None = None) -> Path:
    """Write the CSVs (named as in ``meta.demonstrations``), ``truth.yaml`` and, last, ``meta.yaml``, each
    atomically: a writer stopped half-way leaves no ``meta.yaml`` that names a missing or half-written
    recording. Returns the folder."""
    if len(demos) != len(meta.demonstrations):
        raise InputError("demos", f"{len(meta.demonstrations)} demonstrations (as meta.demonstrations)", len(demos))
    root = Path(folder)
    root.mkdir(parents=True, exist_ok=True)
    for name, demo in zip(meta.demonstrations, demos, strict=True):
        write_demonstration(root / name, demo)
    if truth is not None:
        write_text(root / "truth.yaml", yaml.safe_dump(truth, sort_keys=False))
    write_text(root / "meta.yaml", yaml.safe_dump(meta.model_dump(mode="json"), sort_keys=False))
    return root


def _open_csv(path: Path, root: Path | None = None) -> io.StringIO:
    """The UTF-8 text of a CSV file (a byte-order mark dropped): a regular file inside the dataset folder
    ``root``, of at most :data:`MAX_CSV_BYTES` (:func:`tooltransfer.regular_file.read_regular`)."""
    from tooltransfer.regular_file import read_regular

    raw, where = read_regular(path, DatasetError, "CSV file", MAX_CSV_BYTES, inside=root), str(path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        hint = ", a UTF-16 file?" if raw[:2] in (b"\xff\xfe", b"\xfe\xff") else ""
        raise DatasetError(where, f"row {line}", "a UTF-8 text CSV file",
                           f"a byte that is not UTF-8 (0x{raw[exc.start]:02x}{hint})") from None
    if "\x00" in text:
        line = text.count("\n", 0, text.index("\x00")) + 1
        raise DatasetError(where, f"row {line}", "a text CSV file", "a NUL byte (a binary file?)")
    return io.StringIO(text, newline="")


def _read_csv(path: Path, root: Path | None = None) -> tuple[Demonstration, NDArray[np.int64], NDArray[np.int64]]:
    """One demonstration CSV (inside the dataset folder ``root``), streamed row by row into compact
    arrays (at most :data:`MAX_ROWS` rows), and the CSV row of each object and tool sample."""
    where = str(path)
    fh = _open_csv(path, root)
    reader = csv.reader(fh)
    try:
        header = next(reader, None)
        if header is None:
            raise DatasetError(where, "row 1", f"a header with columns {', '.join(COLUMNS)}", "an empty file")
        header = [h.strip() for h in header]
        missing = [c for c in COLUMNS if c not in header]
        if missing:
            raise DatasetError(where, "row 1", f"columns {', '.join(COLUMNS)}", f"missing {', '.join(missing)}")
        for c in COLUMNS:
            at = [i + 1 for i, h in enumerate(header) if h == c]
            if len(at) > 1:
                raise DatasetError(where, f"row 1, column {c}", "each column once in the header",
                                   f"{c} {len(at)} times (columns {', '.join(map(str, at))})")
        idx = [header.index(c) for c in COLUMNS]
        width = max(idx) + 1
        t_o, t_t, o, k = array("d"), array("d"), array("d"), array("d")
        r_o, r_t = array("q"), array("q")
        last = -math.inf
        r = 1
        for row in reader:
            r += 1
            if r - 1 > MAX_ROWS:
                raise DatasetError(where, f"row {r}", f"at most {MAX_ROWS} data rows in one CSV",
                                   "more (split long recordings into several demonstrations)")
            if len(row) < width:
                if not any(cell.strip() for cell in row):
                    continue  # a blank line
                row = row + [""] * (width - len(row))
            cells = [row[i].strip() for i in idx]
            if not any(cells):
                continue
            vals: list[float | None] = []
            for col, raw in zip(COLUMNS, cells, strict=True):
                if raw == "":
                    vals.append(None)
                    continue
                try:
                    v = float(raw)
                except ValueError:
                    raise DatasetError(where, f"row {r}, column {col}", "a number",
                                       repr(raw if len(raw) <= 40 else raw[:37] + "...")) from None
                if not math.isfinite(v):
                    raise DatasetError(where, f"row {r}, column {col}", "a finite number", raw)
                vals.append(v)
            t = vals[0]
            if t is None:
                raise DatasetError(where, f"row {r}, column t", "a time [s]", "an empty cell")
            if t <= last:
                raise DatasetError(where, f"row {r}, column t", f"a time after the previous row's {last}", t)
            last = t
            obj, tool = vals[1:3], vals[3:]
            for group, cols in ((obj, OBJECT_COLUMNS), (tool, TOOL_COLUMNS)):
                if None in group and any(v is not None for v in group):
                    col = cols[group.index(None)]
                    raise DatasetError(where, f"row {r}, column {col}", "a value (its stream's other cells are "
                                       "filled)", "an empty cell")
            if obj[0] is None and tool[0] is None:
                raise DatasetError(where, f"row {r}", "object or tool values next to the time", "only a time")
            if obj[0] is not None:
                t_o.append(t)
                o.extend(obj)  # type: ignore[arg-type]
                r_o.append(r)
            if tool[0] is not None:
                t_t.append(t)
                k.extend(tool)  # type: ignore[arg-type]
                r_t.append(r)
    except csv.Error as exc:
        raise DatasetError(where, f"row {reader.line_num}", "a CSV file", str(exc)) from None
    for n, what, cols in ((len(t_o), "object", OBJECT_COLUMNS), (len(t_t), "tool", TOOL_COLUMNS)):
        if n < MIN_SAMPLES:
            raise DatasetError(where, f"columns {', '.join(cols)}", f"at least {MIN_SAMPLES} {what} samples", n)
    ka = np.frombuffer(k, dtype=np.float64).reshape(-1, 6).copy()
    demo = Demonstration(path.stem, np.frombuffer(t_o, dtype=np.float64).copy(),
                         np.frombuffer(o, dtype=np.float64).reshape(-1, 2).copy(),
                         np.frombuffer(t_t, dtype=np.float64).copy(), ka[:, :3], ka[:, 3:])
    return demo, np.frombuffer(r_o, dtype=np.int64).copy(), np.frombuffer(r_t, dtype=np.int64).copy()


def load_meta(folder: str | Path) -> Meta:
    """Read and validate ``meta.yaml`` of a dataset folder (errors name the field path)."""
    from tooltransfer.yaml_file import read_yaml

    meta_path = Path(folder) / "meta.yaml"
    raw = read_yaml(meta_path, DatasetError, "meta.yaml", inside=folder)
    try:
        return Meta.model_validate(raw)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = ".".join(str(p) for p in err["loc"]) or "<root>"
        got = err.get("input")
        got = type(got).__name__ if isinstance(got, dict | list) else (repr(got) if len(repr(got)) <= 80
                                                                        else repr(got)[:77] + "...")
        raise DatasetError(str(meta_path), f"field {loc}", err["msg"].removeprefix("Value error, "), got) from None


def load_dataset(folder: str | Path) -> Dataset:
    """Load and check a dataset folder (see the module docstring for the format).

    Besides the format, the values must be plausible for the declared platform and tool: the
    declared tool's ``a_t`` is the platform's, each stream's sampling rate is within
    :data:`RATE_FACTOR` of ``rates`` (times in seconds), the object and tool streams cover the same
    time, joints lie within the Omni's limits widened by :data:`JOINT_SLACK`, tool and object
    positions within its reach region grown by :data:`REACH_SLACK` (positions in metres, not
    millimetres). The segmentation (:func:`tooltransfer.planner.learning.segmentation.segment`) checks the rest against
    the recordings themselves: the tool poses against the joints' forward kinematics, and the contacts
    against the declared tool's outline.

    Raises:
        DatasetError: naming the file (and row and column, or field) of the first problem.
    """
    root = Path(folder)
    meta = load_meta(root)
    meta_path = str(root / "meta.yaml")
    from tooltransfer.regular_file import is_inside
    from tooltransfer.tools.errors import ToolSpecError
    from tooltransfer.tools.library import library_names, read_tool_file

    if meta.tool not in library_names():
        tool_path = root / meta.tool
        if not is_inside(tool_path, root):
            raise DatasetError(meta_path, "field tool", "a library tool, or a tool YAML path inside the dataset",
                               "a path that leads outside it (a link, or ..)")
        if not tool_path.is_file():
            raise DatasetError(meta_path, "field tool", f"a library tool ({', '.join(library_names())}) "
                               "or a tool YAML path relative to the dataset", repr(meta.tool[:80]))
        try:
            read_tool_file(tool_path)  # a regular file of bounded size (tooltransfer.yaml_file.read_text)
        except ToolSpecError as exc:
            raise DatasetError(str(tool_path), "<file>", "a valid tool file", str(exc)) from None
    ds = Dataset(root, meta, ())
    tool = ds.tool()
    if abs(tool.a_t - meta.platform.a_t) > 1e-6:
        raise DatasetError(meta_path, "field tool", "the tool the recordings were made with (its a_t is the "
                           f"platform's a_t = {meta.platform.a_t:g} m)",
                           f"{meta.tool!r}, whose a_t is {tool.a_t:g} m")
    demos = []
    for name in meta.demonstrations:
        demo, rows_o, rows_t = _read_csv(root / name, root)
        origin = Origin(str(root / name), meta_path, meta.tool, meta.platform, float(meta.object_radius), rows_o,
                        rows_t)
        demo = Demonstration(demo.name, demo.t_object, demo.object_xy, demo.t_tool, demo.tool_pose, demo.joints,
                             origin)
        _check_plausible(demo, meta, tool)
        demos.append(demo)
    return Dataset(root, meta, tuple(demos), _read_truth(root / "truth.yaml", meta))


def _check_plausible(demo: Demonstration, meta: Meta, tool: Tool) -> None:
    """The checks of :func:`load_dataset` that need no segmentation (its docstring)."""
    assert demo.origin is not None
    where, o = demo.origin.csv, demo.origin
    for t, rows, declared, key in ((demo.t_object, o.object_rows, meta.rates.object_hz, "object_hz"),
                                   (demo.t_tool, o.tool_rows, meta.rates.tool_hz, "tool_hz")):
        step = float(np.median(np.diff(t)))
        if not 1.0 / RATE_FACTOR <= declared * step <= RATE_FACTOR:
            raise DatasetError(where, "column t", f"samples about every {1 / declared:.4g} s as meta.yaml "
                               f"rates.{key} = {declared:g} Hz says (times in seconds)",
                               f"a median step of {step:.4g} s ({1 / step:.4g} Hz) from row {rows[0]}")
    lo, hi = max(demo.t_object[0], demo.t_tool[0]), min(demo.t_object[-1], demo.t_tool[-1])
    shorter = min(np.ptp(demo.t_object), np.ptp(demo.t_tool))
    if hi - lo < 0.5 * shorter:
        raise DatasetError(where, "column t", "object and tool samples over the same time (one recording, one "
                           "clock)", f"object {demo.t_object[0]:.6g}-{demo.t_object[-1]:.6g} s, tool "
                           f"{demo.t_tool[0]:.6g}-{demo.t_tool[-1]:.6g} s")
    from tooltransfer.tools.omni.platform import DEFAULT_LIMITS

    lower = np.asarray(DEFAULT_LIMITS.lower) - JOINT_SLACK
    upper = np.asarray(DEFAULT_LIMITS.upper) + JOINT_SLACK
    bad = (demo.joints < lower) | (demo.joints > upper)
    if bad.any():
        k, j = (int(v) for v in np.argwhere(bad)[0])
        raise DatasetError(where, f"row {o.tool_rows[k]}, column q{j + 1}", f"a joint angle in radians within "
                           f"the Omni's range [{lower[j]:.3g}, {upper[j]:.3g}] rad", f"{demo.joints[k, j]:g} "
                           "(degrees?)" if abs(demo.joints[k, j]) > 2 * np.pi else f"{demo.joints[k, j]:g}")
    import shapely

    reach = _reach_region(meta.platform.a_t, *meta.platform.base_xy, meta.platform.base_yaw,
                          meta.platform.table_height)
    extent = float(np.max(np.hypot(*np.asarray(tool.outline.exterior.coords).T)))
    for xy, rows, cols, slack in ((demo.tool_pose[:, :2], o.tool_rows, "tool_x, tool_y", REACH_SLACK),
                                  (demo.object_xy, o.object_rows, "obj_x, obj_y",
                                   REACH_SLACK + extent + float(meta.object_radius))):
        step = max(1, xy.shape[0] // 2000)  # plausibility: a subsample suffices, the first outlier below
        far = shapely.distance(reach, shapely.points(xy[::step])) > slack
        if far.any():
            k = int(np.argmax(far)) * step
            raise DatasetError(where, f"row {rows[k]}, columns {cols}", "positions in metres within the Omni's "
                               f"reach (its table region grown by {1e3 * slack:.0f} mm)",
                               f"({xy[k, 0]:g}, {xy[k, 1]:g}) (millimetres?)")


@lru_cache(maxsize=16)
def _reach_region(a_t: float, x: float, y: float, yaw: float, height: float) -> Any:
    """The Omni's reachable table region (shapely) for a dataset's platform."""
    from tooltransfer.tools.omni.platform import OmniPlatform
    from tooltransfer.tools.omni.reach import reachable_polygon

    return reachable_polygon(OmniPlatform(a_t=a_t, base_xy=(x, y), base_yaw=yaw, table_height=height))


class _Push(BaseModel):
    model_config = ConfigDict(extra="allow")

    face: str
    t_start: Number
    t_end: Number


class _DemoTruth(BaseModel):
    model_config = ConfigDict(extra="allow")

    pushes: list[_Push] = []
    switches: list[dict[str, Any]] = []


def _read_truth(path: Path, meta: Meta) -> dict[str, Any] | None:
    """``truth.yaml`` (optional): a mapping whose demonstration entries (CSV stems) are mappings with
    ``pushes`` (face, t_start, t_end) and ``switches`` lists; errors name the file and the field."""
    if not path.exists() and not path.is_symlink():  # a FIFO or a link is read (and refused) below
        return None
    from tooltransfer.yaml_file import read_yaml

    truth = read_yaml(path, DatasetError, "truth.yaml", inside=path.parent)
    if truth is None:
        return None
    if not isinstance(truth, dict):
        raise DatasetError(str(path), "<root>", "a mapping of demonstration names to their ground truth",
                           f"a {type(truth).__name__}")
    stems = {Path(n).stem for n in meta.demonstrations}
    for key, entry in truth.items():
        if not isinstance(key, str):
            raise DatasetError(str(path), f"key {str(key)[:40]!r}", "demonstration names (strings)",
                               type(key).__name__)
        if key not in stems:
            continue  # free-form notes
        try:
            _DemoTruth.model_validate(entry)
        except ValidationError as exc:
            err = exc.errors()[0]
            loc = ".".join(str(p) for p in (key, *err["loc"]))
            got = err.get("input")
            raise DatasetError(str(path), f"field {loc}", err["msg"].removeprefix("Value error, "),
                               repr(got)[:80] if not isinstance(got, dict | list) else type(got).__name__) from None
    return truth
