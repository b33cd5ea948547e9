"""One value for what the task fixes about the world a plan acts in: the object (its radius and push
mechanics), the obstacles and the safety margin, and how much of the friction cone a plan may use.

Every planning stage takes a :class:`Scene` instead of module constants, so a task with a 24 mm
puck, a slippery tool or a wider margin is planned for what it says.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from tooltransfer.errors import InputError
from tooltransfer.problems.task import SAFETY_MARGIN, OEOptions, schema_default
from tooltransfer.tools.objects import Obstacle
from tooltransfer.tools.pushing.mechanics import PLATFORM_MECHANICS, PushMechanics

#: Default share of the friction cone's half-angle a plan may use (``oe.friction_cone_fraction``, the task schema's).
CONE_FRACTION: float = schema_default(OEOptions, "friction_cone_fraction")
#: Default distance [m] the contact keeps from the ends of a face's usable range (``oe.contact_margin``).
CONTACT_MARGIN: float = schema_default(OEOptions, "contact_margin")
#: Default longest stretch [m] of a face the contact may use, about its middle (``oe.contact_span``).
CONTACT_SPAN: float = schema_default(OEOptions, "contact_span")


@dataclass(frozen=True)
class Scene:
    """The object, its mechanics and the obstacles, as one planning input.

    Attributes:
        radius: the object's radius [m].
        mechanics: the push model's parameters (tool-object friction ``mu``, limit-surface ``c``).
        obstacles: discs and convex polygons in the world [m].
        margin: safety margin [m] kept from the obstacles beyond the radius (the one the plan can
            keep: see :func:`tooltransfer.planner.solve.effective_margin`).
        cone_fraction: share (0, 1] of the friction cone's half-angle ``atan(mu)`` the planned
            object directions may use about a face's normal, so that the plan survives an error in
            ``mu`` (a fraction 0.5 still sticks with a true ``mu`` of ``tan(atan(mu) / 2)``).
        contact_margin: distance [m] the contact keeps from the ends of a face's usable range.
        contact_span: longest stretch [m] of a face the contact may use, about its middle: the
            Omni's reach is planned for the tool poses of contacts at both ends of that stretch.
    """

    radius: float
    mechanics: PushMechanics = field(default_factory=lambda: PLATFORM_MECHANICS)
    obstacles: tuple[Obstacle, ...] = ()
    margin: float = SAFETY_MARGIN
    cone_fraction: float = CONE_FRACTION
    contact_margin: float = CONTACT_MARGIN
    contact_span: float = CONTACT_SPAN

    def __post_init__(self) -> None:
        for name in ("radius", "margin", "contact_margin", "contact_span"):
            v = getattr(self, name)
            if not isinstance(v, int | float | np.floating) or not np.isfinite(v) or v < 0 or \
                    (name == "radius" and v <= 0):
                raise InputError(f"scene.{name}", "a finite length [m]" + (" > 0" if name == "radius" else " >= 0"),
                                 repr(v))
            object.__setattr__(self, name, float(v))
        if not isinstance(self.mechanics, PushMechanics):
            raise InputError("scene.mechanics", "a PushMechanics", type(self.mechanics).__name__)
        if not 0.0 < float(self.cone_fraction) <= 1.0:
            raise InputError("oe.friction_cone_fraction", "a number in (0, 1]", repr(self.cone_fraction))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))

    @property
    def cone_half_angle(self) -> float:
        """Half-angle [rad] about a face's normal that planned object directions may use."""
        return self.cone_fraction * self.mechanics.friction_angle

    def with_obstacles(self, obstacles: Sequence[Obstacle]) -> Scene:
        """The same scene with other obstacles."""
        return Scene(self.radius, self.mechanics, tuple(obstacles), self.margin, self.cone_fraction,
                     self.contact_margin, self.contact_span)
