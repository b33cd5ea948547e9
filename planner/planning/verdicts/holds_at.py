"""Where on each face the contact can hold the puck at one position: what an ``unknown`` verdict leaves open.

A task is left ``unknown`` where the search found no plan and no certificate was proved. One cause the
search's own reason cannot show is a hold so narrow that the search's contact windows miss it: at the start
(or the target) the Omni reaches the puck with a face and keeps the tool outline clear of the obstacles only
with the contact within a fraction of a millimetre of one end of that face (``exec60-00020`` and
``verd200-00049`` of the verdict benchmark, benchmarks/README.md). :func:`face_holds` measures that, for one
puck position and every face that can push: along the face's contact range (:data:`HOLD_SAMPLES` places),
the contacts at which the Omni holds the puck within its joints (the pose of
:mod:`~tooltransfer.planner.planning.verdicts.rules`, the arm reaching forward) and the tool outline keeps the
hard check's :data:`~tooltransfer.planner.planning.tool_clearance.TOOL_MARGIN` from every obstacle. The
stretches of such contacts are a face's *windows*.

A description, not a proof: the places are samples (a window between two of them, or one end of a window, is
known to the spacing of the samples only), and a hold says nothing about the pushes from there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.face_frame import FaceFrame, admissible_cone
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN, outline_distances
from tooltransfer.planner.planning.verdicts.hold_windows import NARROW_HOLD

#: Contact places sampled along each face's contact range (a window's ends are known to one spacing).
HOLD_SAMPLES = 201


@dataclass(frozen=True)
class FaceHold:
    """Where face ``face`` can hold the puck at one position (module docstring).

    Attributes:
        face: the face's name.
        length: the face's length [m].
        windows: the stretches ``(lo, hi)`` [m] along the face (from its start) of the contacts at which the
            Omni holds the puck and the tool keeps :data:`TOOL_MARGIN` from the obstacles; empty: none.
        reached: how many of the sampled contacts the Omni reaches within its joints.
        clearance: the largest distance [m] between the tool outline and the obstacles over the reached
            contacts (0 where every one overlaps an obstacle, inf without obstacles, NaN where none is reached).
    """

    face: str
    length: float
    windows: tuple[tuple[float, float], ...]
    reached: int
    clearance: float

    @property
    def widest(self) -> float:
        """The widest window [m] (0 for one sampled contact; -1 where there is none, as
        :func:`~.hold_windows.widest_stored`)."""
        return max((hi - lo for lo, hi in self.windows), default=-1.0)

    def to_dict(self) -> dict[str, Any]:
        """JSON data (non-finite clearances as None)."""
        return {"face": self.face, "length": self.length, "windows": [list(w) for w in self.windows],
                "reached": self.reached, "clearance": self.clearance if math.isfinite(self.clearance) else None}


def face_holds(setting: Setting, p: NDArray[np.float64], samples: int = HOLD_SAMPLES) -> list[FaceHold]:
    """Per face that can push (its admissible cone at the whole friction cone not empty, as
    :func:`~.rules.push_rules` keeps it), where along it the contact holds the puck at ``p`` (2,) [m] in
    ``setting`` (module docstring), in the tool's order: each sampled contact's :class:`FaceFrame` places the tool
    (the arm reaching forward) and its outline is measured by :func:`outline_distances`."""
    p = np.asarray(p, dtype=np.float64)
    friction = setting.mechanics.friction_angle
    out = []
    for face in setting.tool.faces:
        lo, hi = admissible_cone(face.normal_angle, face.push_angle, face.theta_b, friction)
        if hi < lo:
            continue
        s = np.linspace(face.contact_range[0], face.contact_range[1], samples)
        frames = [FaceFrame.build(setting, face.name, s=float(si), friction_cone_fraction=1.0) for si in s]
        reached = np.array([_reaches(f, p) for f in frames])
        clear = np.full(samples, math.inf)
        if setting.obstacles:
            poses = np.vstack([f.tool_pose(p[None]) for f in frames])
            clear = outline_distances(setting.tool, poses, list(setting.obstacles)).min(axis=0)
        held = reached & (clear >= TOOL_MARGIN)
        out.append(FaceHold(face.name, float(face.length), _runs(held, s * face.length), int(reached.sum()),
                            float(clear[reached].max()) if reached.any() else math.nan))
    return out


def _reaches(frame: FaceFrame, p: NDArray[np.float64]) -> bool:
    """Whether the Omni holds ``frame``'s contact on the puck at ``p`` (2,) [m] within its joints, the arm reaching
    forward: ``p`` farther from its axis than the offset, the waist angle and the arm-plane reach in range."""
    r2 = float(np.sum((p - frame.base) ** 2))
    if r2 <= frame.offset ** 2:
        return False
    a = float(frame.waist_angle(p[None])[0])
    v = math.sqrt(r2 - frame.offset ** 2)
    return frame.waist[0] <= a <= frame.waist[1] and frame.reach[0] <= v <= frame.reach[1]


def _runs(held: NDArray[np.bool_], at: NDArray[np.float64]) -> tuple[tuple[float, float], ...]:
    """The ``(first, last)`` of ``at`` over each run of consecutive True in ``held``."""
    runs, begin = [], None
    for k, h in enumerate(held):
        if h and begin is None:
            begin = k
        if begin is not None and (not h or k == len(held) - 1):
            end = k if h else k - 1
            runs.append((float(at[begin]), float(at[end])))
            begin = None
    return tuple(runs)


def narrow_hold(holds: list[FaceHold], where: str) -> str:
    """A clause saying that the puck at ``where`` ("the start", "the target") is held only on windows narrower
    than :data:`NARROW_HOLD` (the widest of them named), or that no face holds it there at all; "" where some
    face holds it on a window at least that wide. (:data:`NARROW_HOLD` is the guided search's narrowest window
    with the default ``oe.guided_contact_span``; a task that sets another is measured against the default.)"""
    best = max(holds, key=lambda h: h.widest, default=None)
    if best is None or best.widest < 0.0:
        return (f"at {where} no face holds the puck at any of its {HOLD_SAMPLES} sampled contacts with the Omni in "
                f"its joints and the tool {TOOL_MARGIN * 1e3:g} mm clear of the obstacles")
    if best.widest >= NARROW_HOLD:
        return ""
    near = f"; the tool at most {best.clearance * 1e3:.2g} mm from an obstacle" if math.isfinite(best.clearance) else ""
    return (f"at {where} the contact holds the puck only on {best.widest * 1e3:.2g} mm of {best.face!r} "
            f"(a {best.length * 1e3:.3g} mm face{near}), narrower than the guided search's narrowest windows "
            f"({NARROW_HOLD * 1e3:g} mm with its default contact span)")

