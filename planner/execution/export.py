"""A plan's joint trajectory for a real arm (``tooltransfer export``): CSV, NumPy ``.npz``, or JSON
shaped like ROS ``trajectory_msgs/msg/JointTrajectory``.

Each holds, per sample of the plan, the time from the start [s] and the joints' positions [rad],
velocities [rad/s] and accelerations [rad/s^2] (:func:`tooltransfer.planner.planning.plan.joint_rates`), under the
joints' names (the plan's ``joint_names``, or others for a robot's description):

- ``csv``: a header ``t,<name>_position,...,<name>_velocity,...,<name>_acceleration,...,phase``, one
  row per sample, numbers as Python writes them (they read back exactly), the plan's phase last;
- ``npz``: arrays ``t`` (T,), ``positions``, ``velocities``, ``accelerations`` (T, 3),
  ``joint_names`` (3,) and ``phase`` (T,) strings (``numpy.load`` without pickles);
- ``joint-trajectory``: ``{"header": {"stamp": {"sec", "nanosec"}, "frame_id"}, "joint_names": [...],
  "points": [{"positions", "velocities", "accelerations", "effort": [], "time_from_start": {"sec",
  "nanosec"}}, ...]}``, the fields of the ROS 2 message and nothing else, so
  ``rosidl_runtime_py.set_message_fields(JointTrajectory(), json.load(f))`` fills the message (the
  times rounded to the nanosecond).

:func:`read_trajectory` reads any of them back (the round trip is exact but for those nanoseconds).
Files are written atomically (:mod:`tooltransfer.atomic`).
"""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.planning.plan import JOINT_NAMES, Plan
from tooltransfer.readable_json import dumps

FORMATS = ("csv", "npz", "joint-trajectory")
#: The file name ending of each format (the default output is the plan's name with it).
SUFFIXES = {"csv": ".csv", "npz": ".npz", "joint-trajectory": ".trajectory.json"}


@dataclass(frozen=True)
class Trajectory:
    """A joint trajectory: ``t`` (T,) [s] from the start, ``positions`` (T, 3) [rad], ``velocities``
    (T, 3) [rad/s], ``accelerations`` (T, 3) [rad/s^2], ``joint_names`` (3,) and the plan's ``phase``
    (T,) (empty when the file has none: a JointTrajectory message)."""

    t: NDArray[np.float64]
    positions: NDArray[np.float64]
    velocities: NDArray[np.float64]
    accelerations: NDArray[np.float64]
    joint_names: tuple[str, ...] = JOINT_NAMES
    phase: tuple[str, ...] = ()

    @classmethod
    def from_plan(cls, plan: Plan, joint_names: tuple[str, ...] | None = None) -> Trajectory:
        """The plan's joint trajectory, under ``joint_names`` (default: the plan's)."""
        names = tuple(joint_names) if joint_names is not None else tuple(plan.joint_names)
        return cls(plan.t, plan.joints, plan.joint_velocities, plan.joint_accelerations,
                   check_joint_names(names), tuple(plan.phase))


def check_joint_names(names: tuple[str, ...] | list[str], field: str = "--joint-names") -> tuple[str, ...]:
    """``names`` if they are 3 distinct names of 1-100 printable characters without commas, else
    :class:`~tooltransfer.errors.InputError` naming ``field``."""
    expected = "3 distinct joint names (1 to 100 printable characters, no commas), e.g. waist,shoulder,elbow"
    if len(names) != 3 or len(set(names)) != 3 or not all(
            isinstance(n, str) and 0 < len(n) <= 100 and n.isprintable() and "," not in n for n in names):
        raise InputError(field, expected, ",".join(map(str, names))[:200])
    return tuple(names)


def default_output(plan_path: str | Path, fmt: str) -> Path:
    """The export's default path: the plan file's name with the format's ending
    (``out/plan.json`` -> ``out/plan.trajectory.json`` for ``joint-trajectory``)."""
    p = Path(plan_path)
    stem = p.name[: -len(p.suffix)] if p.suffix else p.name
    return p.with_name((stem or "plan") + SUFFIXES[fmt])


def _duration(t: float) -> dict[str, int]:
    """``t`` [s] as a ROS ``builtin_interfaces/Duration`` (``nanosec`` in [0, 1e9))."""
    sec = math.floor(t)
    nanosec = round((t - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"sec": int(sec), "nanosec": int(nanosec)}


def joint_trajectory_message(traj: Trajectory) -> dict[str, Any]:
    """The trajectory as the fields of a ROS 2 ``trajectory_msgs/msg/JointTrajectory`` (module docstring)."""
    return {
        "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
        "joint_names": list(traj.joint_names),
        "points": [{"positions": p, "velocities": v, "accelerations": a, "effort": [],
                    "time_from_start": _duration(t)}
                   for t, p, v, a in zip(traj.t.tolist(), traj.positions.tolist(), traj.velocities.tolist(),
                                         traj.accelerations.tolist(), strict=True)],
    }


#: One point of :func:`joint_trajectory_text` as :func:`tooltransfer.readable_json.dumps` lays it out in
#: the message (the arrays' numbers, the seconds and the nanoseconds put in).
_POINT = ('\n  {\n   "positions": [%s],\n   "velocities": [%s],\n   "accelerations": [%s],\n   "effort": [],'
          '\n   "time_from_start": {\n    "sec": %d,\n    "nanosec": %d\n   }\n  }')


def _rows(values: NDArray[np.float64]) -> list[str]:
    """Each row of ``values`` (T, 3) as JSON writes the numbers of a list (``a, b, c``), from one call of
    the encoder on them all (rows of numbers hold no bracket: the text splits at ``], [``)."""
    text = _JSON_ROWS.encode(values.tolist())
    return text[2:-2].split("], [") if len(values) else []


_JSON_ROWS = json.JSONEncoder(allow_nan=True, separators=(", ", ": "))


def joint_trajectory_text(traj: Trajectory) -> str:
    """``dumps(joint_trajectory_message(traj)) + "\n"`` (:func:`tooltransfer.readable_json.dumps`), the
    same text written from a template: the header and the names by ``dumps``, every point by
    :data:`_POINT`, its numbers by three calls of the JSON encoder for all points (twice as quick as
    laying out the message's thousands of objects one by one)."""
    head = dumps({"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
                  "joint_names": list(traj.joint_names)})
    if not len(traj.t):
        return head[:-2] + ',\n "points": []\n}\n'
    times = [_duration(t) for t in traj.t.tolist()]
    points = ",".join([_POINT % (p, v, a, d["sec"], d["nanosec"]) for p, v, a, d in zip(
        _rows(traj.positions), _rows(traj.velocities), _rows(traj.accelerations), times, strict=True)])
    return head[:-2] + ',\n "points": [' + points + "\n ]\n}\n"


def _csv_text(traj: Trajectory) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    names = traj.joint_names
    w.writerow(["t", *(f"{n}_position" for n in names), *(f"{n}_velocity" for n in names),
                *(f"{n}_acceleration" for n in names), "phase"])
    rows = np.column_stack([traj.t, traj.positions, traj.velocities, traj.accelerations]).tolist()
    phases = traj.phase or ("",) * len(rows)
    for row, phase in zip(rows, phases, strict=True):
        w.writerow([repr(x) for x in row] + [phase])
    return buf.getvalue()


def export_plan(plan: Plan, out: str | Path, fmt: str, joint_names: tuple[str, ...] | None = None) -> Path:
    """Write ``plan``'s joint trajectory to ``out`` in format ``fmt`` (:data:`FORMATS`) under
    ``joint_names`` (default: the plan's); returns the path."""
    from tooltransfer.atomic import atomic_path, write_text

    if fmt not in FORMATS:
        raise InputError("--format", f"one of {', '.join(FORMATS)}", fmt)
    traj = Trajectory.from_plan(plan, joint_names)
    if fmt == "csv":
        return write_text(out, _csv_text(traj))
    if fmt == "joint-trajectory":
        return write_text(out, joint_trajectory_text(traj))
    with atomic_path(out) as tmp, open(tmp, "wb") as f:  # a file object: numpy adds no ".npz" to the name
        np.savez(f, t=traj.t, positions=traj.positions, velocities=traj.velocities,
                 accelerations=traj.accelerations, joint_names=np.array(traj.joint_names),
                 phase=np.array(traj.phase, dtype=str))
    return Path(out)


#: Largest text trajectory read back [bytes] (a regular file, its size checked before it is read).
MAX_READ_BYTES = 256 * 2**20


def _fail(path: Path, field: str, expected: str, got: object | None = None) -> InputError:
    return InputError(f"{path}: {field}", expected, got)


def _format_of(path: Path) -> str:
    name = path.name.lower()
    for fmt, suffix in sorted(SUFFIXES.items(), key=lambda kv: -len(kv[1])):
        if name.endswith(suffix):
            return fmt
    return "joint-trajectory" if name.endswith(".json") else ""


def read_trajectory(path: str | Path, fmt: str | None = None) -> Trajectory:
    """Read an exported trajectory (format ``fmt``, default from the file's ending) back.

    Raises:
        InputError: naming the file and the field (or the row) that is missing or malformed.
    """
    from tooltransfer.regular_file import read_regular

    p = Path(path)
    fmt = fmt or _format_of(p)
    if fmt not in FORMATS:
        raise _fail(p, "<file>", f"a file of one of the formats {', '.join(FORMATS)} (ending "
                    f"{', '.join(SUFFIXES.values())})", p.name)
    try:
        if fmt == "npz":
            with np.load(p, allow_pickle=False) as z:
                missing = [k for k in ("t", "positions", "velocities", "accelerations", "joint_names") if k not in z]
                if missing:
                    raise _fail(p, missing[0], "an array (t, positions, velocities, accelerations, joint_names)")
                phase = [str(x) for x in z["phase"]] if "phase" in z else []
                return _checked(p, z["t"], z["positions"], z["velocities"], z["accelerations"],
                                [str(n) for n in z["joint_names"]], phase)
        text = read_regular(p, lambda _p, w, e, g: _fail(p, w, e, g), f"{fmt} file", MAX_READ_BYTES).decode("utf-8")
    except InputError:  # the file refused by name (read_regular)
        raise
    except OSError as exc:
        raise _fail(p, "<file>", "a readable file", exc.strerror) from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise _fail(p, "<file>", f"a {fmt} file", str(exc)[:100]) from None
    if fmt == "csv":
        return _read_csv(p, text)
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise _fail(p, f"line {exc.lineno}, column {exc.colno}", "valid JSON", exc.msg) from None
    if not isinstance(doc, dict) or not isinstance(doc.get("points"), list):
        raise _fail(p, "points", "a JointTrajectory mapping with a list of points")
    cols: dict[str, list[Any]] = {"positions": [], "velocities": [], "accelerations": []}
    t = []
    for i, point in enumerate(doc["points"]):
        if not isinstance(point, dict):
            raise _fail(p, f"points[{i}]", "a JointTrajectoryPoint mapping")
        for key, col in cols.items():
            col.append(point.get(key))
        d = point.get("time_from_start")
        if not isinstance(d, dict) or not all(type(d.get(k)) is int for k in ("sec", "nanosec")):
            raise _fail(p, f"points[{i}].time_from_start", "a Duration {sec, nanosec} of integers")
        t.append(d["sec"] + 1e-9 * d["nanosec"])
    names = doc.get("joint_names")
    if not isinstance(names, list):
        raise _fail(p, "joint_names", "a list of 3 names")
    return _checked(p, t, cols["positions"], cols["velocities"], cols["accelerations"], names, [])


def _read_csv(p: Path, text: str) -> Trajectory:
    rows = list(csv.reader(io.StringIO(text)))
    if not rows or len(rows[0]) != 11 or rows[0][0] != "t" or rows[0][-1] != "phase":
        raise _fail(p, "header", "t, 3 positions, 3 velocities, 3 accelerations and phase")
    head = rows[0]
    names = [h.removesuffix("_position") for h in head[1:4]]
    try:
        data = np.array([[float(x) for x in r[:10]] for r in rows[1:]], dtype=np.float64).reshape(-1, 10)
    except ValueError as exc:
        raise _fail(p, "rows", "10 numbers and a phase per row", str(exc)[:100]) from None
    return _checked(p, data[:, 0], data[:, 1:4], data[:, 4:7], data[:, 7:10], names, [r[10] for r in rows[1:]])


def _checked(p: Path, t: Any, pos: Any, vel: Any, acc: Any, names: list[Any], phase: list[str]) -> Trajectory:
    try:
        tt = np.asarray(t, dtype=np.float64).reshape(-1)
        arrays = [np.asarray(a, dtype=np.float64).reshape(len(tt), 3) for a in (pos, vel, acc)]
    except (TypeError, ValueError) as exc:
        raise _fail(p, "<arrays>", "3 numbers of each kind per sample", str(exc)[:100]) from None
    if not all(np.isfinite(a).all() for a in (tt, *arrays)):
        raise _fail(p, "<arrays>", "finite numbers")
    if phase and len(phase) != len(tt):
        raise _fail(p, "phase", f"{len(tt)} phases like t", len(phase))
    return Trajectory(tt, arrays[0], arrays[1], arrays[2], check_joint_names(names, f"{p}: joint_names"), tuple(phase))


def run_export(args: Any) -> int:
    """``tooltransfer export PLAN --format F [-o OUT] [--joint-names a,b,c] [--force]``: the plan read
    and checked against itself and its task (:func:`tooltransfer.planner.execution.simulate.check_plan`, as ``simulate``
    does: ``--force`` exports one that fails, with a warning), then written. Exit 0 written, 1 the
    plan is infeasible (or violated, without ``--force``); errors raise (the command line's exit 2)."""

    from tooltransfer.planner.common.command_line import EXIT_INFEASIBLE, EXIT_OK, check_output

    names = check_joint_names(args.joint_names.split(",")) if args.joint_names is not None else None
    out = Path(args.out) if args.out is not None else default_output(args.plan, args.format)
    check_output("-o/--out", out)  # before any work (an explicit -o is checked by the command line already)
    if out.exists() and Path(args.plan).exists() and out.samefile(args.plan):
        raise InputError("-o/--out", "a file other than the plan", str(out))
    from tooltransfer.planner.execution.simulate import plan_to_use

    # checked against itself and its task before an arm runs it (a hand-edited plan may lie)
    plan = plan_to_use(args.plan, args.force, "exports", "exporting", "; nothing exported")
    if plan is None:
        return EXIT_INFEASIBLE
    path = export_plan(plan, out, args.format, names)
    shown = ", ".join(names or plan.joint_names)
    print(f"wrote {path} ({args.format}: {plan.t.size} points over {plan.t[-1] - plan.t[0]:.2f} s, joints {shown})")
    return EXIT_OK
