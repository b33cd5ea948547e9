"""Plan files: a versioned, self-describing JSON record of a solved (or infeasible) task.

Everything a checker needs is inside, in SI units, so a plan can be verified without this code:
the task as loaded, the platform (DH rows, base pose, table height, joint limits, a_t), the object,
the tool (outline in the tool frame, faces with push direction and cone half-angle), obstacles,
equal-length sample arrays (time, object centre, tool pose, joints, the joints' velocities and
accelerations, phase, face), the joints' names, the pushes and switches, and metrics with their
units beside them (``metric_units``: metric name to ``"m"``, ``"rad"``, ``"s"`` or ``""`` for a count
or a ratio, from :data:`tooltransfer.planner.common.metric_units.UNITS`; a QP family's ``violation_<family>``,
in its rows' units, has none). Format
``tooltransfer.plan/1``; :func:`read_plan` refuses other versions and files that do not hold together
(an unknown status, unequal sample arrays, values that are not finite numbers, unknown phases,
non-increasing time, a metric unit that is not the metric's), naming the file and the field.

The joint velocities [rad/s] and accelerations [rad/s^2] are the derivatives of the joints on the
plan's times, as the simulated execution tracks them (:func:`joint_rates`: ``numpy.gradient`` of the
joints over ``t``, then of the velocities; second-order central differences inside, one-sided at
the ends); through the Omni's Jacobian they give the tool path's velocity to second order in the
sample spacing. Plan files written before they were added (no ``joint_velocities``,
``joint_accelerations`` or ``joint_names``) are read with them derived so, and the names of the
simulated Omni's joints (:data:`JOINT_NAMES`); plan files without ``metric_units`` are read too (the
units are those of :data:`~tooltransfer.planner.common.metric_units.UNITS` either way). A plan's status is
``solved``, ``infeasible`` (no whole plan: the reason says why) or ``violated`` (a whole plan that
breaks a hard check, :func:`tooltransfer.planner.planning.solve.hard_check_failures`: the reason names the families).
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.common.metric_units import UNIT_NAMES, UNITS

FORMAT = "tooltransfer.plan/1"
PHASES = ("approach", "push", "switch", "retreat")
#: Names of the Omni's three joints (waist, shoulder, elbow) as the simulated Omni's model has them
#: (``tooltransfer.tools.sim.mjcf.ARM_JOINTS``); ``tooltransfer export --joint-names`` renames them for a robot.
JOINT_NAMES = ("q1", "q2", "q3")

Phase = Literal["approach", "push", "switch", "retreat"]


class PlanFileError(InputError):
    """A plan file is unreadable, of another version, or inconsistent."""

    def __init__(self, path: str, field: str, expected: str, got: object | None = None) -> None:
        self.path = path
        super().__init__(f"{path}: {field}", expected, got)


@dataclass(frozen=True)
class Segment:
    """A push or a switch on the plan's time axis.

    Attributes:
        kind: ``"push"`` or ``"switch"``.
        t_start, t_end: [s].
        faces: the pushing face (push) or ``(from, to)`` (switch).
        info: extra numbers (e.g. the switch's min clearance [m], the push direction [rad]).
    """

    kind: str
    t_start: float
    t_end: float
    faces: tuple[str, ...]
    info: dict[str, float] = field(default_factory=dict)


def joint_rates(t: NDArray[np.float64], joints: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The joints' velocities (T, 3) [rad/s] and accelerations (T, 3) [rad/s^2] on the times ``t`` (T,) [s]:
    ``numpy.gradient`` of ``joints`` (T, 3) [rad] over ``t``, then of the velocities (second-order
    central differences on the uneven grid inside, first-order one-sided at the ends: what the
    simulated execution feeds forward, :func:`tooltransfer.tools.sim.reference.joint_reference`). Zeros for fewer
    than 2 samples."""
    t = np.asarray(t, dtype=np.float64)
    q = np.asarray(joints, dtype=np.float64).reshape(len(t), -1)
    if t.size < 2:
        return np.zeros_like(q), np.zeros_like(q)
    v = np.asarray(np.gradient(q, t, axis=0), dtype=np.float64)
    return v, np.asarray(np.gradient(v, t, axis=0), dtype=np.float64)


@dataclass(frozen=True)
class Plan:
    """A plan. ``samples`` arrays: ``t`` (T,) [s], ``object_xy`` (T, 2) [m], ``tool_pose`` (T, 3)
    (x, y [m], yaw [rad]), ``joints`` (T, 3) [rad], ``joint_velocities`` (T, 3) [rad/s],
    ``joint_accelerations`` (T, 3) [rad/s^2], ``phase`` (T,) strings, ``face`` (T,) names or None;
    ``joint_names`` names the joints' columns. The joints' velocities and accelerations, when not
    given, are derived from the joints (:func:`joint_rates`)."""

    status: Literal["solved", "infeasible", "unknown", "violated"]
    variant: dict[str, str]
    task: dict[str, Any]
    platform: dict[str, Any]
    object: dict[str, Any]
    tool: dict[str, Any]
    obstacles: list[dict[str, Any]]
    t: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    object_xy: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    tool_pose: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    joints: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    phase: tuple[str, ...] = ()
    face: tuple[str | None, ...] = ()
    pushes: tuple[Segment, ...] = ()
    switches: tuple[Segment, ...] = ()
    metrics: dict[str, float] = field(default_factory=dict)
    reason: str = ""
    joint_velocities: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    joint_accelerations: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    joint_names: tuple[str, ...] = JOINT_NAMES
    evidence: dict[str, Any] = field(default_factory=dict)

    @property
    def verdict(self) -> Literal["solved", "infeasible", "unknown"]:
        """The task's verdict: ``"solved"`` (every hard check holds), ``"infeasible"`` (a certificate
        in :attr:`evidence` proves that no plan exists under the rules it states) or ``"unknown"``
        (neither: the search found no plan, or only one that breaks a hard check, ``"violated"``)."""
        if self.status == "violated":
            return "unknown"
        return self.status

    @property
    def planning_time(self) -> float:
        """The solve's time [s] (``solve --json``'s ``planning_time``): the metric ``time_total``, else the
        stages' times (``time_*``) summed: a plan that stopped early has no total."""
        m = self.metrics
        return float(m["time_total"]) if "time_total" in m else float(sum(v for k, v in m.items()
                                                                              if k.startswith("time_")))

    def __post_init__(self) -> None:
        n = len(self.t)
        if len(self.joint_velocities) != n or len(self.joint_accelerations) != n:
            v, a = joint_rates(self.t, self.joints) if len(self.joints) == n else (np.zeros((n, 3)),) * 2
            object.__setattr__(self, "joint_velocities", v if len(self.joint_velocities) != n else
                               self.joint_velocities)
            object.__setattr__(self, "joint_accelerations", a if len(self.joint_accelerations) != n else
                               self.joint_accelerations)

    def to_dict(self) -> dict[str, Any]:
        """The JSON document (plain Python types; non-finite numbers become strings)."""

        def seg(s: Segment) -> dict[str, Any]:
            return {"t_start": s.t_start, "t_end": s.t_end, "faces": list(s.faces), **_clean(s.info)}

        return {
            "format": FORMAT,
            "status": self.status,
            "reason": self.reason,
            "variant": self.variant,
            "task": self.task,
            "platform": self.platform,
            "object": self.object,
            "tool": self.tool,
            "obstacles": self.obstacles,
            "joint_names": list(self.joint_names),
            "samples": {
                "t": self.t.tolist(),
                "object_xy": self.object_xy.tolist(),
                "tool_pose": self.tool_pose.tolist(),
                "joints": self.joints.tolist(),
                "joint_velocities": self.joint_velocities.tolist(),
                "joint_accelerations": self.joint_accelerations.tolist(),
                "phase": list(self.phase),
                "face": list(self.face),
            },
            "pushes": [seg(s) for s in self.pushes],
            "switches": [seg(s) for s in self.switches],
            "metrics": _clean(self.metrics),
            "metric_units": metric_units(self.metrics),
            "verdict": self.verdict,
            "evidence": self.evidence,
        }

    def write(self, path: str | Path) -> Path:
        """Write the plan as JSON (objects indented, sampled arrays one per line:
        :mod:`tooltransfer.readable_json`), atomically (a temporary file beside it replaces it once complete:
        :mod:`tooltransfer.atomic`, so no half-written plan is ever left); returns the path."""
        from tooltransfer.atomic import write_text
        from tooltransfer.readable_json import dumps

        return write_text(path, dumps(self.to_dict()))


def metric_units(metrics: dict[str, Any]) -> dict[str, str]:
    """The units of the ``metrics`` listed in :data:`~tooltransfer.planner.common.metric_units.UNITS` (name to
    ``"m"``, ``"rad"``, ``"s"`` or ``""``), in the metrics' order: the plan file's ``metric_units``."""
    return {k: UNITS[k] for k in metrics if k in UNITS}


def _clean(d: dict[str, Any]) -> dict[str, Any]:
    return {k: (v if not isinstance(v, float) or np.isfinite(v) else str(v)) for k, v in d.items()}


def _num(d: dict[str, Any]) -> dict[str, float]:
    return {k: float(v) for k, v in d.items() if isinstance(v, int | float | str) and _is_number(v)}


def _is_number(v: object) -> bool:
    if isinstance(v, bool):
        return False
    try:
        float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return True


def _kind(v: object) -> str:
    """A short description of a JSON value for messages (never the whole value)."""
    if isinstance(v, str):
        return repr(v if len(v) <= 40 else v[:37] + "...")
    if isinstance(v, bool) or v is None or isinstance(v, int | float):
        return json.dumps(v)
    return f"a {'list' if isinstance(v, list) else 'mapping' if isinstance(v, dict) else type(v).__name__}"


def _numbers(where: str, name: str, value: object, width: int | None, unit: str,
             bound: float = 1e6) -> NDArray[np.float64]:
    """``value`` as a float array (T,) or (T, width), every entry a finite JSON number (not a bool,
    a string or null) within ``[-bound, bound]``; errors name ``samples.<name>[i][j]``."""
    field = f"samples.{name}"
    if not isinstance(value, list):
        raise PlanFileError(where, field, "a list" + (f" of [{width} numbers] rows" if width else " of numbers"),
                            _kind(value))
    if not _all_numbers(value, width):  # then the first bad row or entry, named
        _first_not_number(where, field, value, width, unit)
    arr = np.array(value, dtype=np.float64).reshape((len(value), width) if width else (len(value),))
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(arr) <= bound)
    if bad.any():
        k = np.argwhere(bad)[0]
        at = f"{field}[{k[0]}]" + (f"[{k[1]}]" if width is not None else "")
        v = float(arr[tuple(k)])
        raise PlanFileError(where, at, f"a finite number {unit}" + ("" if not np.isfinite(v) else
                            f" within +-{bound:g}"), v)
    return arr


def _all_numbers(value: list[Any], width: int | None) -> bool:
    """Whether every entry of ``value`` (or of each of its rows, lists of ``width``) is a JSON number
    (``float`` or ``int``, not a bool): the types gathered by C loops, as quick as reading them."""
    if width is None:
        return set(map(type, value)) <= _NUMBER_TYPES
    return (set(map(type, value)) <= {list} and set(map(len, value)) <= {width}
            and set(map(type, itertools.chain.from_iterable(value))) <= _NUMBER_TYPES)


_NUMBER_TYPES = frozenset((float, int))


def _first_not_number(where: str, field: str, value: list[Any], width: int | None, unit: str) -> None:
    """Raise the :class:`PlanFileError` of the first row of ``value`` that is not a list of ``width``
    numbers (or the first entry that is not a number), if there is one."""
    for i, row in enumerate(value):
        cells = row if width is not None else [row]
        if width is not None and (not isinstance(row, list) or len(row) != width):
            raise PlanFileError(where, f"{field}[{i}]", f"a row of {width} numbers {unit}", _kind(row))
        for j, x in enumerate(cells):
            if type(x) is not float and type(x) is not int:
                at = f"{field}[{i}]" + (f"[{j}]" if width is not None else "")
                raise PlanFileError(where, at, f"a number {unit}", _kind(x))


#: Largest plan file read [bytes] and largest number of samples (a plan of 2,000 samples takes about
#: 0.5 MB; the planner's plans sample about 90 Hz, so 200,000 samples are over half an hour).
MAX_PLAN_BYTES = 64 * 2**20
MAX_SAMPLES = 200_000
#: Statuses a plan file may hold: ``violated`` is a whole plan that breaks a hard check
#: (:func:`tooltransfer.planner.planning.solve.hard_check_failures`).
STATUSES = ("solved", "infeasible", "unknown", "violated")
#: Bounds of the joints' velocities [rad/s] and accelerations [rad/s^2] read (the Omni's plans stay
#: within a few rad/s and some tens of rad/s^2; beyond these is junk, not a plan).
MAX_JOINT_VELOCITY, MAX_JOINT_ACCELERATION = 1e6, 1e9


def _document(where: str, p: Path) -> dict[str, Any]:
    """The plan file ``p`` read (a regular file of at most ``MAX_PLAN_BYTES``, UTF-8), parsed as JSON
    and of this ``FORMAT``; the first problem raised as a :class:`PlanFileError` naming the file."""
    from tooltransfer.regular_file import read_regular

    try:
        size = p.stat().st_size
        if size > MAX_PLAN_BYTES:
            raise PlanFileError(where, "<file>", f"a plan file of at most {MAX_PLAN_BYTES // 2**20} MB",
                                f"{size / 2**20:.0f} MB")
        text = read_regular(p, lambda _p, w, e, g: PlanFileError(where, w, e, g), "plan file",
                            MAX_PLAN_BYTES).decode("utf-8-sig")  # a regular file, read without blocking
    except OSError as exc:
        raise PlanFileError(where, "<file>", "a readable plan file", exc.strerror) from None
    except UnicodeDecodeError as exc:
        raise PlanFileError(where, "<file>", "a UTF-8 JSON plan file",
                            f"a byte that is not UTF-8 at offset {exc.start}") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PlanFileError(where, f"line {exc.lineno}, column {exc.colno}", "valid JSON", exc.msg) from None
    except RecursionError:
        raise PlanFileError(where, "<file>", "JSON of a plan (not nested thousands of levels deep)") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = _kind(doc.get("format")) if isinstance(doc, dict) else _kind(doc)
        raise PlanFileError(where, "format", f"{FORMAT!r}", got)
    return doc


def _parts(where: str, doc: dict[str, Any]) -> dict[str, Any]:
    """The plan's mappings and lists (variant, task, platform, object, tool, obstacles, metrics),
    with variant names as strings and metrics as numbers (or strings)."""
    parts: dict[str, Any] = {}
    for key, kind in (("variant", dict), ("task", dict), ("platform", dict), ("object", dict), ("tool", dict),
                      ("obstacles", list), ("metrics", dict)):
        v = doc.get(key, kind())
        if not isinstance(v, kind):
            raise PlanFileError(where, key, f"a {'list' if kind is list else 'mapping'}", _kind(v))
        parts[key] = v
    bad_variant = [k for k, v in parts["variant"].items() if not isinstance(v, str)]
    if bad_variant:
        k = bad_variant[0]
        raise PlanFileError(where, f"variant.{k}", "a variant name", _kind(parts["variant"][k]))
    bad_metric = [k for k, v in parts["metrics"].items() if isinstance(v, bool) or not isinstance(v, int | float | str)]
    if bad_metric:
        k = bad_metric[0]
        raise PlanFileError(where, f"metrics.{k}", "a number", _kind(parts["metrics"][k]))
    if "metric_units" in doc:  # optional: plan files before it lack it
        _check_metric_units(where, doc["metric_units"], parts["metrics"])
    return parts



def _check_metric_units(where: str, units: object, metrics: dict[str, Any]) -> None:
    """``metric_units`` checked: a mapping from names in ``metrics`` to a unit string, the one
    :data:`~tooltransfer.planner.common.metric_units.UNITS` gives the name where it lists it."""
    if not isinstance(units, dict):
        raise PlanFileError(where, "metric_units", "a mapping of metric names to units", _kind(units))
    for k, u in units.items():
        if k not in metrics:
            raise PlanFileError(where, f"metric_units.{k}", "the unit of a metric in metrics", _kind(u))
        if not isinstance(u, str) or u not in UNIT_NAMES:
            raise PlanFileError(where, f"metric_units.{k}", f"one of {', '.join(map(repr, UNIT_NAMES))}", _kind(u))
        if k in UNITS and u != UNITS[k]:
            raise PlanFileError(where, f"metric_units.{k}", f"{UNITS[k]!r} (the unit {k} is in)", _kind(u))


def _sample_arrays(where: str, s: dict[str, Any]) -> tuple[NDArray[np.float64], dict[str, NDArray[np.float64]]]:
    """The times (T,) [s] and the numeric sample arrays of the mapping ``s`` (each at most
    ``MAX_SAMPLES`` long, finite and bounded; the joint rates only where the file has them)."""
    for name, v in s.items():
        if isinstance(v, list) and len(v) > MAX_SAMPLES:
            raise PlanFileError(where, f"samples.{name}", f"at most {MAX_SAMPLES} samples", len(v))
    t = _numbers(where, "t", s["t"], None, "[s]", 1e7)
    arrays = {  # positions within 10 m of the origin, angles within 100 rad: beyond is junk, not a plan
        "object_xy": _numbers(where, "object_xy", s["object_xy"], 2, "[m]", 10.0),
        "tool_pose": _numbers(where, "tool_pose", s["tool_pose"], 3, "(x, y [m], yaw [rad])", 100.0),
        "joints": _numbers(where, "joints", s["joints"], 3, "[rad]", 100.0),
    }
    for name, unit, bound in (("joint_velocities", "[rad/s]", MAX_JOINT_VELOCITY),
                              ("joint_accelerations", "[rad/s^2]", MAX_JOINT_ACCELERATION)):
        if name in s:  # optional: plan files before them lack them (derived from the joints then)
            arrays[name] = _numbers(where, name, s[name], 3, unit, bound)
    return t, arrays


def _labels(where: str, s: dict[str, Any], t: NDArray[np.float64], arrays: dict[str, NDArray[np.float64]],
            status: str) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """The per-sample phase and face labels, after checking that every sample array is as long as
    ``t``, ``t`` increases, the labels are known and a solved or violated plan has two samples."""
    for name in ("phase", "face"):
        if not isinstance(s[name], list):
            raise PlanFileError(where, f"samples.{name}", "a list", _kind(s[name]))
    phase, face = tuple(s["phase"]), tuple(s["face"])
    for name, arr in (*arrays.items(), ("phase", phase), ("face", face)):
        if len(arr) != t.size:
            raise PlanFileError(where, f"samples.{name}", f"{t.size} entries like samples.t", len(arr))
    if t.size > 1 and np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0)) + 1
        raise PlanFileError(where, f"samples.t[{k}]", f"a time after samples.t[{k - 1}] = {t[k - 1]:.6g} s", t[k])
    for i, x in enumerate(phase):
        if x not in PHASES:
            raise PlanFileError(where, f"samples.phase[{i}]", f"one of {', '.join(PHASES)}", _kind(x))
    for i, x in enumerate(face):
        if x is not None and not isinstance(x, str):
            raise PlanFileError(where, f"samples.face[{i}]", "a face name or null", _kind(x))
    if status in ("solved", "violated") and t.size < 2:
        raise PlanFileError(where, "samples.t", f"at least 2 samples in a {status} plan", t.size)
    return phase, face


def _segments(where: str, doc: dict[str, Any], key: str, kind: str) -> tuple[Segment, ...]:
    """The segments listed under ``key`` (pushes or switches, of ``kind``): finite times [s], not
    ending before they start, face names; their other fields kept as numbers."""
    items = doc.get(key, [])
    if not isinstance(items, list):
        raise PlanFileError(where, key, "a list of {t_start, t_end, faces}", _kind(items))
    out = []
    for i, e in enumerate(items):
        if not isinstance(e, dict):
            raise PlanFileError(where, f"{key}[{i}]", "a mapping with t_start, t_end and faces", _kind(e))
        for k in ("t_start", "t_end"):
            v = e.get(k)
            if isinstance(v, bool) or not isinstance(v, int | float) or not np.isfinite(v):
                raise PlanFileError(where, f"{key}[{i}].{k}", "a finite time [s]", _kind(v))
        if e["t_end"] < e["t_start"]:
            raise PlanFileError(where, f"{key}[{i}].t_end", f"a time not before t_start = {e['t_start']}",
                                e["t_end"])
        faces = e.get("faces")
        if not isinstance(faces, list) or not all(isinstance(f, str) for f in faces):
            raise PlanFileError(where, f"{key}[{i}].faces", "a list of face names", _kind(faces))
        info = _num({k: v for k, v in e.items() if k not in ("t_start", "t_end", "faces")})
        out.append(Segment(kind, float(e["t_start"]), float(e["t_end"]), tuple(faces), info))
    return tuple(out)


def read_plan(path: str | Path) -> Plan:
    """Read and check a plan file: the format, a known status, equal-length sample arrays of finite
    numbers (joints numbers, not booleans), known phases, increasing time, pushes and switches with
    finite times; errors name the file and the field (e.g. ``samples.joints[12][1]``).

    Raises:
        PlanFileError: the first problem found.
    """
    p = Path(path)
    where = str(p)
    doc = _document(where, p)
    status = doc.get("status", "")
    if status not in STATUSES:
        raise PlanFileError(where, "status", f"one of {', '.join(STATUSES)}", _kind(status))
    reason = doc.get("reason", "")
    if not isinstance(reason, str):
        raise PlanFileError(where, "reason", "a string", _kind(reason))
    parts = _parts(where, doc)
    evidence = doc.get("evidence", {})
    if not isinstance(evidence, dict):
        raise PlanFileError(where, "evidence", "a mapping (the verdict's evidence)", _kind(evidence))
    s = doc.get("samples")
    if not isinstance(s, dict):
        raise PlanFileError(where, "samples", "a mapping of arrays t, object_xy, tool_pose, joints, phase, face",
                            _kind(s))
    missing = [k for k in ("t", "object_xy", "tool_pose", "joints", "phase", "face") if k not in s]
    if missing:
        raise PlanFileError(where, f"samples.{missing[0]}", "an array (samples: t, object_xy, tool_pose, joints, "
                            "phase, face)", "none")
    t, arrays = _sample_arrays(where, s)
    joint_names = _joint_names(where, doc.get("joint_names", list(JOINT_NAMES)))
    phase, face = _labels(where, s, t, arrays, status)
    return Plan(
        status=status, variant=parts["variant"], task=parts["task"], platform=parts["platform"],
        object=parts["object"], tool=parts["tool"], obstacles=parts["obstacles"], t=t, phase=phase, face=face,
        pushes=_segments(where, doc, "pushes", "push"), switches=_segments(where, doc, "switches", "switch"),
        metrics=_num(parts["metrics"]), reason=reason, joint_names=joint_names, evidence=evidence, **arrays,
    )


def _joint_names(where: str, names: object) -> tuple[str, ...]:
    """``joint_names`` checked: 3 distinct names of 1-100 printable characters."""
    if not isinstance(names, list) or len(names) != 3:
        raise PlanFileError(where, "joint_names", "a list of 3 joint names", _kind(names))
    for i, name in enumerate(names):
        if not isinstance(name, str) or not 0 < len(name) <= 100 or not name.isprintable():
            raise PlanFileError(where, f"joint_names[{i}]", "a name of 1 to 100 printable characters", _kind(name))
    if len(set(names)) != 3:
        raise PlanFileError(where, "joint_names", "3 distinct names", ", ".join(names))
    return tuple(names)
