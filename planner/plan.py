"""Plan files: a versioned, self-describing JSON record of a solved (or infeasible) task.

Everything a checker needs is inside, in SI units, so a plan can be verified without this code:
the task as loaded, the platform (DH rows, base pose, table height, joint limits, a_t), the object,
the tool (outline in the tool frame, faces with push direction and cone half-angle), obstacles,
equal-length sample arrays (time, object centre, tool pose, joints, phase, face), the pushes and
switches, and metrics. Format ``tooltransfer.plan/1``; :func:`read_plan` refuses other versions and
files that do not hold together (unequal sample arrays, unknown phases, non-increasing time).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from dmp.errors import InputError

FORMAT = "tooltransfer.plan/1"
PHASES = ("approach", "push", "switch", "retreat")

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


@dataclass(frozen=True)
class Plan:
    """A plan. ``samples`` arrays: ``t`` (T,) [s], ``object_xy`` (T, 2) [m], ``tool_pose`` (T, 3)
    (x, y [m], yaw [rad]), ``joints`` (T, 3) [rad], ``phase`` (T,) strings, ``face`` (T,) names or None."""

    status: Literal["solved", "infeasible"]
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
            "samples": {
                "t": self.t.tolist(),
                "object_xy": self.object_xy.tolist(),
                "tool_pose": self.tool_pose.tolist(),
                "joints": self.joints.tolist(),
                "phase": list(self.phase),
                "face": list(self.face),
            },
            "pushes": [seg(s) for s in self.pushes],
            "switches": [seg(s) for s in self.switches],
            "metrics": _clean(self.metrics),
        }

    def write(self, path: str | Path) -> Path:
        """Write the plan as JSON; returns the path."""
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(json.dumps(self.to_dict(), indent=1))
        return p


def _clean(d: dict[str, Any]) -> dict[str, Any]:
    return {k: (v if not isinstance(v, float) or np.isfinite(v) else str(v)) for k, v in d.items()}


def _num(d: dict[str, Any]) -> dict[str, float]:
    return {k: float(v) for k, v in d.items() if isinstance(v, int | float | str) and _is_number(v)}


def _is_number(v: object) -> bool:
    try:
        float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return True


def read_plan(path: str | Path) -> Plan:
    """Read and check a plan file."""
    p = Path(path)
    where = str(p)
    try:
        doc = json.loads(p.read_text())
    except OSError as exc:
        raise PlanFileError(where, "<file>", "a readable plan file", exc.strerror) from None
    except json.JSONDecodeError as exc:
        raise PlanFileError(where, f"line {exc.lineno}, column {exc.colno}", "valid JSON", exc.msg) from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise PlanFileError(where, "format", f"{FORMAT!r}", got)
    try:
        s = doc["samples"]
        t = np.asarray(s["t"], dtype=np.float64)
        arrays = {
            "object_xy": np.asarray(s["object_xy"], dtype=np.float64).reshape(-1, 2),
            "tool_pose": np.asarray(s["tool_pose"], dtype=np.float64).reshape(-1, 3),
            "joints": np.asarray(s["joints"], dtype=np.float64).reshape(-1, 3),
        }
        phase, face = tuple(s["phase"]), tuple(s["face"])
    except (KeyError, TypeError, ValueError) as exc:
        raise PlanFileError(where, "samples", "arrays t, object_xy, tool_pose, joints, phase, face", exc) from None
    for name, arr in (*arrays.items(), ("phase", phase), ("face", face)):
        if len(arr) != t.size:
            raise PlanFileError(where, f"samples.{name}", f"{t.size} entries like samples.t", len(arr))
    if t.size > 1 and np.any(np.diff(t) <= 0):
        raise PlanFileError(where, "samples.t", "increasing times")
    bad = [x for x in phase if x not in PHASES]
    if bad:
        raise PlanFileError(where, "samples.phase", f"one of {', '.join(PHASES)}", bad[0])

    def segs(key: str, kind: str) -> tuple[Segment, ...]:
        out = []
        for i, e in enumerate(doc.get(key, [])):
            try:
                info = _num({k: v for k, v in e.items() if k not in ("t_start", "t_end", "faces")})
                out.append(Segment(kind, float(e["t_start"]), float(e["t_end"]), tuple(e["faces"]), info))
            except (KeyError, TypeError, ValueError) as exc:
                raise PlanFileError(where, f"{key}[{i}]", "t_start, t_end and faces", exc) from None
        return tuple(out)

    return Plan(
        status=doc.get("status", ""), variant=doc.get("variant", {}), task=doc.get("task", {}),
        platform=doc.get("platform", {}), object=doc.get("object", {}), tool=doc.get("tool", {}),
        obstacles=doc.get("obstacles", []), t=t, phase=phase, face=face, pushes=segs("pushes", "push"),
        switches=segs("switches", "switch"), metrics=_num(doc.get("metrics", {})), reason=doc.get("reason", ""),
        **arrays,
    )
