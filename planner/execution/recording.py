"""Recording files: what executions of a plan on the simulated platform did, for a viewer
(``tooltransfer simulate PLAN --record REC.json``, read by ``tooltransfer view PLAN --execution REC.json``).

Format ``tooltransfer.recording/1``, JSON::

    {"format": "tooltransfer.recording/1", "plan": "<the plan file's path as given>",
     "executions": {"open loop": {"t_object": [...], "object_xy": [[x, y], ...],
                                  "t_tool": [...], "tool_pose": [[x, y, yaw], ...],
                                  "contacts": [{"t_start", "t_end", "face"}, ...]},
                    "closed loop": {...}}}

Times [s] on the platform's clock, positions [m], yaw [rad]
(:class:`tooltransfer.tools.sim.execution.Execution`); the tool track is kept at most every
:data:`TOOL_STEP` [s] (the viewer's resolution, not the encoders'). :func:`read_recording` also
takes a saved ``simulate --json`` summary that names a recording (``"record"``), and refuses
anything else naming the file and the field.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tooltransfer.errors import InputError

if TYPE_CHECKING:
    from tooltransfer.tools.sim.execution import Execution

FORMAT = "tooltransfer.recording/1"
#: Shortest time between two kept tool samples [s].
TOOL_STEP = 0.02


def recording_dict(executions: dict[str, Execution], plan: str) -> dict[str, Any]:
    """The recording document of ``executions`` (by mode: ``"open loop"``, ``"closed loop"``) of the
    plan file ``plan``."""
    import numpy as np

    out: dict[str, Any] = {}
    for mode, e in executions.items():
        keep = np.zeros(len(e.t_tool), dtype=bool)
        last = -math.inf
        for i, t in enumerate(e.t_tool):
            if t - last >= TOOL_STEP - 1e-9 or i == len(e.t_tool) - 1:
                keep[i], last = True, t
        out[mode] = {"t_object": np.round(e.t_object, 4).tolist(), "object_xy": np.round(e.object_xy, 6).tolist(),
                     "t_tool": np.round(e.t_tool[keep], 4).tolist(),
                     "tool_pose": np.round(e.tool_pose[keep], 6).tolist(),
                     "contacts": [{"t_start": c.t_start, "t_end": c.t_end, "face": c.face} for c in e.contacts]}
    return {"format": FORMAT, "plan": plan, "executions": out}


def write_recording(path: str | Path, executions: dict[str, Execution], plan: str) -> Path:
    """Write :func:`recording_dict` to ``path`` atomically; returns it."""
    from tooltransfer.atomic import write_text

    return write_text(path, json.dumps(recording_dict(executions, plan), separators=(",", ":")) + "\n")


def _series(doc: Any, where: str, key: str, width: int) -> list[list[float]] | list[float]:
    v = doc.get(key) if isinstance(doc, dict) else None
    ok = isinstance(v, list) and all(
        (isinstance(x, int | float) and math.isfinite(x)) if width == 0 else
        (isinstance(x, list) and len(x) == width and all(isinstance(y, int | float) and math.isfinite(y) for y in x))
        for x in v)
    if not ok:
        shape = "a list of finite numbers" if width == 0 else f"a list of [{width} finite numbers]"
        raise InputError(f"{where}: {key}", shape, type(v).__name__ if not isinstance(v, list) else "other values")
    return v  # type: ignore[return-value]


def read_recording(path: str | Path) -> dict[str, dict[str, Any]]:
    """The executions of the recording file ``path`` by mode (module docstring); a ``simulate --json``
    summary with a ``"record"`` path is followed (as given, else relative to the summary's folder).

    Raises:
        InputError: the file is missing, not JSON, of another format, or its series are not lists of
            finite numbers of equal lengths (naming the file and the field).
    """
    p = Path(path)
    try:
        doc = json.loads(p.read_text())
    except OSError as exc:
        raise InputError(f"{p}", "a recording file (tooltransfer simulate PLAN --record FILE)",
                         exc.strerror or str(exc)) from None
    except ValueError as exc:
        raise InputError(f"{p}", "a recording file in JSON", f"not JSON ({exc})") from None
    if isinstance(doc, dict) and "format" not in doc and isinstance(doc.get("record"), str):
        rec = Path(doc["record"])  # as given to simulate: from where it ran, else beside the summary
        return read_recording(rec if rec.is_absolute() or rec.exists() else p.parent / rec)
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise InputError(f"{p}: format", f"{FORMAT!r} (tooltransfer simulate PLAN --record FILE)", got)
    runs = doc.get("executions")
    if not isinstance(runs, dict) or not runs:
        raise InputError(f"{p}: executions", "an object of executions by mode", type(runs).__name__)
    out: dict[str, dict[str, Any]] = {}
    for mode, e in runs.items():
        where = f"{p}: executions.{mode}"
        t_o, xy = _series(e, where, "t_object", 0), _series(e, where, "object_xy", 2)
        t_t, pose = _series(e, where, "t_tool", 0), _series(e, where, "tool_pose", 3)
        if len(t_o) != len(xy) or len(t_t) != len(pose):
            raise InputError(where, "t_object as long as object_xy and t_tool as long as tool_pose",
                             f"{len(t_o)}/{len(xy)} and {len(t_t)}/{len(pose)}")
        contacts = e.get("contacts") or []
        if not isinstance(contacts, list):
            raise InputError(f"{where}: contacts", "a list of contact events", type(contacts).__name__)
        out[str(mode)] = {"t_object": t_o, "object_xy": xy, "t_tool": t_t, "tool_pose": pose, "contacts": contacts}
    return out
