"""The result of planning a switch, in domain words: the one type every switch and re-contact planner
returns (the SS variants ``dmp`` and ``opt``, the geometric ``arch``, the re-contact move) and
:func:`tooltransfer.planner.planning.assemble.assemble` times."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from tooltransfer.tools.contact import Contact

Status = Literal["solved", "infeasible", "failed"]


@dataclass(frozen=True)
class SwitchPath:
    """A switch path (or why there is none).

    Attributes:
        variant: ``"dmp"`` (recombination, eq. 18), ``"opt"`` (CasADi NLP), ``"arch"`` (the geometric
            reference), ``"grid"`` (the search over the tool's placements) or ``"recontact"`` (the same face
            touching again elsewhere).
        status: ``"solved"``; ``"infeasible"`` (no such path: unreachable contact pose, a contact pose
            inside the object or an obstacle, or the NLP found no feasible point); ``"failed"`` (the
            solver or the exact check failed otherwise). ``reason`` says why when not solved.
        t: shape (K,), times from the start [s].
        xy: shape (K, 2), tool centre points [m]; yaw: shape (K,), headings (the Omni's) [rad]. The
            geometric planners (``arch``, ``recontact``) give only ``xy`` (``t`` and ``yaw`` empty): the
            assembly times the path and the Omni imposes the heading.
        start, end: the contact poses (None when they could not be computed).
        object_penetration: largest penetration depth [m] of the swept tool into the object.
        object_clearance: smallest clearance [m] from the object away from the two contacts (over
            the middle of the path, where the full margin applies).
        obstacle_penetration, obstacle_clearance: the same against the obstacles (whole path).
        fallback: True when a fallback planner found this path after the primary one found none
            (:func:`tooltransfer.planner.planning.switches.with_fallback`).
        info: numbers of the computation (k1, k2, end correction, solver status, iterations,
            refinements, knots, margin, timings [s]; for ``opt`` every solve in ``attempts`` with the
            start it used, and ``x_start`` (N, 2) [m], the start of the solve returned).
    """

    variant: str
    status: Status
    reason: str = ""
    t: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    xy: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    yaw: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    start: Contact | None = None
    end: Contact | None = None
    object_penetration: float = float("nan")
    object_clearance: float = float("nan")
    obstacle_penetration: float = float("nan")
    obstacle_clearance: float = float("nan")
    fallback: bool = False
    info: dict[str, object] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when solved."""
        return self.status == "solved"

    @property
    def max_penetration(self) -> float:
        """Largest penetration [m] into the object or an obstacle (0 when clear)."""
        return float(max(self.object_penetration, self.obstacle_penetration))
