"""What an execution on the simulated platform recorded: tracks at sensor rates and contact events.

Times are on the platform's clock [s] (0 at :meth:`tooltransfer.tools.sim.platform.SimPlatform.reset`), on the
physics steps: an execution of ``n`` steps starting at step ``k`` records the steps ``k .. k + n - 1``
(the state at the start of each step), so consecutive executions concatenate without duplicates
(:meth:`Execution.concat`) and :meth:`~tooltransfer.tools.sim.platform.SimPlatform.observe` gives the state
after the last step. A stream at ``rate`` [Hz] is sampled at the first physics step at or after
each multiple of ``1 / rate`` on that clock, so chunks share one time grid.

Poses follow :mod:`tooltransfer.tools.pose`: the tool pose ``(x, y, yaw)`` is the planar tool frame of
:mod:`tooltransfer.tools.model` in the world (origin at the tool centre point, yaw its heading, which follows
q1 on the Omni); the object's ``(x, y)`` is the puck's centre, its yaw the puck's rotation about z.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.validation import check_positive

#: Breaks in tool-object contact shorter than this [s] (the puck chattering on the face) are
#: bridged: they stay one :class:`ContactEvent`.
CONTACT_GAP = 0.02


@dataclass(frozen=True)
class Rates:
    """Recording rates [Hz]: ``object_hz`` for the object (a depth camera: about 30 Hz), ``tool_hz``
    for the tool pose, the joints and the per-sample contact flag (the Omni's encoders: at least
    100 Hz). At most the physics rate (1 / timestep)."""

    object_hz: float = 30.0
    tool_hz: float = 200.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "object_hz", check_positive(self.object_hz, "rates.object_hz"))
        object.__setattr__(self, "tool_hz", check_positive(self.tool_hz, "rates.tool_hz"))


@dataclass(frozen=True)
class ContactEvent:
    """A stretch of tool-object contact (breaks under :data:`CONTACT_GAP` bridged).

    Attributes:
        t_start, t_end: first and last physics step in contact [s].
        piece: index of the tool's convex piece (:attr:`tooltransfer.tools.model.Tool.convex_pieces`) touching
            the object at most steps.
        max_penetration: deepest tool-object penetration during the event [m].
        face: name of the tool face (:attr:`tooltransfer.tools.model.Tool.faces`) nearest the contact point at
            most steps (within :data:`tooltransfer.tools.sim.recorder.FACE_TOL`), None when the contact was mostly
            off every face (e.g. on a rounded corner).
    """

    t_start: float
    t_end: float
    piece: int
    max_penetration: float
    face: str | None = None

    @property
    def duration(self) -> float:
        """``t_end - t_start`` [s]."""
        return self.t_end - self.t_start


@dataclass(frozen=True)
class Execution:
    """The recording of one execution (or of consecutive ones, see :meth:`concat`).

    Attributes:
        t_object: shape (M,), object sample times [s].
        object_xy: shape (M, 2), object centre [m] (world frame).
        object_yaw: shape (M,), object rotation about z [rad].
        t_tool: shape (N,), tool and joint sample times [s].
        tool_pose: shape (N, 3), tool frame ``(x, y, yaw)`` [m, m, rad] in the world.
        joints: shape (N, 3), measured joints ``(q1, q2, q3)`` [rad].
        joints_ref: shape (N, 3), the PD reference at the same times [rad].
        contact: shape (N,), whether each tool sample lies in a contact event (the tool touching
            the object, breaks under :data:`CONTACT_GAP` bridged; see :mod:`tooltransfer.tools.sim.recorder`).
        penetration: shape (N,), tool-object penetration depth at each tool sample [m] (0 when the
            collision detection finds no contact at that step).
        contacts: the contact events (every physics step, not only the samples).
    """

    t_object: NDArray[np.float64]
    object_xy: NDArray[np.float64]
    object_yaw: NDArray[np.float64]
    t_tool: NDArray[np.float64]
    tool_pose: NDArray[np.float64]
    joints: NDArray[np.float64]
    joints_ref: NDArray[np.float64]
    contact: NDArray[np.bool_]
    penetration: NDArray[np.float64]
    contacts: tuple[ContactEvent, ...] = field(default=())

    @staticmethod
    def concat(parts: Sequence[Execution]) -> Execution:
        """One recording of consecutive executions (in order); a contact event cut by the boundary
        between two parts (break under :data:`CONTACT_GAP`, same face) becomes one event again."""
        if not parts:
            raise InputError("parts", "at least one Execution", "an empty sequence")
        for i in range(1, len(parts)):
            a, b = parts[i - 1], parts[i]
            ends = [x[-1] for x in (a.t_object, a.t_tool) if x.size]
            starts = [x[0] for x in (b.t_object, b.t_tool) if x.size]
            if ends and starts and min(starts) <= max(ends):
                raise InputError(f"parts[{i}]", "an execution that starts after the previous one ends",
                                 f"t = {min(starts):.4f} s <= {max(ends):.4f} s")
        arrays = {
            f.name: np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(Execution)
            if f.name != "contacts"
        }
        events: list[ContactEvent] = []
        for e in (e for p in parts for e in p.contacts):
            last = events[-1] if events else None
            if last is not None and e.t_start - last.t_end <= CONTACT_GAP and e.face == last.face:
                events[-1] = ContactEvent(last.t_start, e.t_end, last.piece,
                                          max(last.max_penetration, e.max_penetration), last.face)
            else:
                events.append(e)
        return Execution(**arrays, contacts=tuple(events))

    @property
    def tracking_error(self) -> float:
        """Largest joint tracking error ``|q - q_ref|`` over the samples [rad]."""
        return float(np.abs(self.joints - self.joints_ref).max()) if self.joints.size else 0.0

    @property
    def max_penetration(self) -> float:
        """Deepest tool-object penetration over the contact events [m] (0 without contact)."""
        return max((e.max_penetration for e in self.contacts), default=0.0)
