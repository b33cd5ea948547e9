"""The result of condensing an OE skill for a tool: the object path and its ordered pushes."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

Status = Literal["solved", "infeasible"]


@dataclass(frozen=True)
class Push:
    """One push: ``face`` of the tool moves the object during ``[t_start, t_end]`` [s].

    Attributes:
        face: face name.
        t_start, t_end: interval [s] on the plan's time axis.
        direction: mean world direction [rad] of the object's motion during the push.
        samples: indices (K,) into the plan's samples covered by the push.
        tool_pose: shape (K, 3), the tool pose realising it: x, y [m] of the tool centre point and
            yaw [rad], heading as the Omni imposes it, from the inverse push model.
        contact_s: shape (K,), arc length [m] of the contact along the face (from its start).
        recontact: whether the push continues the previous push's face after a re-contact.
        cone_margin: least ``atan(mu) - |phi_c|`` [rad] over the push (how far inside the friction
            cone the object's motion stays).
        edge_margin: least distance [m] of the contact from the ends of the face's usable range.
        frame_s: arc length [m] of the contact the fit's cone rows were written at, where the contact
            kept to a window of the face (:func:`~.sequence_fit.fit_frame`); NaN: the face's middle.
    """

    face: str
    t_start: float
    t_end: float
    direction: float
    samples: NDArray[np.intp]
    tool_pose: NDArray[np.float64]
    contact_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    recontact: bool = False
    cone_margin: float = float("nan")
    edge_margin: float = float("nan")
    frame_s: float = float("nan")


@dataclass(frozen=True)
class PushPlan:
    """Object path and pushes of one OE variant.

    Attributes:
        variant: ``"mapping"`` (the paper) or ``"qp"`` (this project).
        status: ``"solved"`` or ``"infeasible"`` (then ``reason`` says why and the arrays are empty).
        t: sample times (T,) [s].
        object_xy: object centre (T, 2) [m]; object_v: its velocity (T, 2) [m/s].
        universal: the generalized universal path (T, 2) [m] the plan condenses.
        pushes: in time order.
        metrics: see :func:`tooltransfer.planner.planning.oe.metrics.plan_metrics`.
        n_qp: constrained fits solved (``qp`` variant).
        candidates: push sequences scored, each ``(faces, switch times [s], cost or None)``.
        next_best: when set, computes the plan of the next candidate in order of cost (``qp``
            variant), for the planner to fall back on when a later stage fails on this one.
    """

    variant: str
    status: Status
    t: NDArray[np.float64]
    object_xy: NDArray[np.float64]
    object_v: NDArray[np.float64]
    universal: NDArray[np.float64]
    pushes: tuple[Push, ...] = ()
    reason: str = ""
    metrics: dict[str, float] = field(default_factory=dict)
    n_qp: int = 0
    candidates: tuple[tuple[tuple[str, ...], tuple[float, ...], float | None], ...] = ()
    next_best: Callable[[], PushPlan] | None = field(default=None, compare=False, repr=False)

    @property
    def faces(self) -> tuple[str, ...]:
        """Faces of the pushes, in order."""
        return tuple(p.face for p in self.pushes)
