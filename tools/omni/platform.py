"""The Omni platform's placement on the table and its joint limits, in one frozen dataclass.

World frame (docs/design.md section 2): in the table plane, origin under the Omni's first joint axis,
``x`` to the operator's right, ``y`` forward (away from the Omni base), ``z`` up. The Omni base
frame (DH frame 0) has its origin on the joint-1 axis; ``base_yaw`` is the angle of its ``x``
axis in the world, and ``table_height`` is the height of the pushing plane in the base frame.

Defaults: base at the world origin, ``base_yaw = pi/2`` so that ``q1 = 0`` points the arm
forward (+y), and ``table_height = 0``: the Omni stands on the table with DH frame 0 at the table
surface, so the shoulder (joint 2) is d1 = 133.35 mm above the table, and the tool's outline and
the object's centre are taken to lie in the table plane (tool and puck are a few mm thick). With
the default limits and tool 1 the reachable table region is an annular sector of radii 90-217 mm
spanning +-57 degrees about +y, area 0.039 m^2 (see :func:`tooltransfer.tools.omni.reach.reachable_polygon`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.validation import check_array, check_positive


@dataclass(frozen=True)
class JointLimits:
    """Box limits on ``(q1, q2, q3)`` [rad] in the convention of the paper's DH table (Table I).

    Attributes:
        lower: shape (3,) lower bounds [rad].
        upper: shape (3,) upper bounds [rad].
        source: where the values come from, in words.
    """

    lower: tuple[float, float, float]
    upper: tuple[float, float, float]
    source: str = ""

    def __post_init__(self) -> None:
        lo = check_array(self.lower, "limits.lower", shape=(3,))
        hi = check_array(self.upper, "limits.upper", shape=(3,))
        if np.any(lo >= hi):
            j = int(np.argmax(lo >= hi))
            raise InputError(f"limits.lower[{j}]", "lower < upper", f"{lo[j]} >= {hi[j]}")
        object.__setattr__(self, "lower", tuple(float(v) for v in lo))
        object.__setattr__(self, "upper", tuple(float(v) for v in hi))

    def violated(self, q: ArrayLike, atol: float = 1e-9) -> tuple[int, ...]:
        """0-based indices of the joints of ``q`` (3,) [rad] beyond the limits by more than atol."""
        qv = np.asarray(q, dtype=np.float64)
        bad = (qv < np.asarray(self.lower) - atol) | (qv > np.asarray(self.upper) + atol)
        return tuple(int(j) for j in np.flatnonzero(bad))


#: Default joint limits of the Omni in the Table I convention.
#:
#: The paper prints no joint limits, and the Omni's datasheet gives only the workspace box
#: (160 W x 120 H x 70 D mm), not joint ranges. The values are this project's estimates of the
#: mechanical range, expressed in the DH convention of Table I (q2: upper arm below horizontal;
#: q3: forearm relative to upper arm, >= 0 keeps the elbow above the wrist as on the device):
#: q1 in [-1.0, 1.0] (waist, about +-57 deg), q2 in [-0.35, 1.2], q3 in [0.0, 1.6]. At the default
#: table height the reachable region (radii 90-217 mm) contains the published 160 x 70 mm (W x D)
#: footprint centred in front of the base (tested in tests/test_omni_reach.py).
DEFAULT_LIMITS = JointLimits(
    lower=(-1.0, -0.35, 0.0),
    upper=(1.0, 1.2, 1.6),
    source=(
        "project estimate (the paper and the datasheet give none); the table region contains the "
        "Omni's published 160 x 70 mm (W x D) workspace footprint"
    ),
)


@dataclass(frozen=True)
class OmniPlatform:
    """Placement and parameters of the Phantom Omni carrying one tool.

    Attributes:
        a_t: tool length a_t [m] of the tool row of Table I (0.026 for tool 1, 0.028 for tool 2).
        base_xy: shape (2,), world position of the joint-1 axis [m].
        base_yaw: yaw of the base frame's x axis in the world [rad]; pi/2 points q1 = 0 forward.
        table_height: height of the pushing plane in the base frame [m].
        limits: joint limits [rad].
    """

    a_t: float = 0.026
    base_xy: tuple[float, float] = (0.0, 0.0)
    base_yaw: float = np.pi / 2
    table_height: float = 0.0
    limits: JointLimits = field(default=DEFAULT_LIMITS)

    def __post_init__(self) -> None:
        object.__setattr__(self, "a_t", check_positive(self.a_t, "a_t"))
        xy = check_array(self.base_xy, "base_xy", shape=(2,))
        object.__setattr__(self, "base_xy", (float(xy[0]), float(xy[1])))
        for name in ("base_yaw", "table_height"):
            val = check_array(getattr(self, name), name, ndim=0)
            object.__setattr__(self, name, float(val))
        if not isinstance(self.limits, JointLimits):
            raise InputError("limits", "a JointLimits", type(self.limits).__name__)

    def with_a_t(self, a_t: float) -> OmniPlatform:
        """The same platform carrying a tool of length ``a_t`` [m]."""
        return replace(self, a_t=a_t)

    def heading(self, q1: float | NDArray[np.float64]) -> float | NDArray[np.float64]:
        """Yaw [rad] of the planar tool frame in the world for waist angle ``q1`` [rad].

        The planar tool frame's +y axis points along the arm (away from the base), so the heading
        is ``base_yaw + q1 - pi/2``; with the defaults it equals ``q1``.
        """
        return self.base_yaw + q1 - np.pi / 2

    def base_to_world(self, p_base: ArrayLike) -> NDArray[np.float64]:
        """Map points (..., 3) from the base frame to the world frame [m]."""
        p = np.asarray(p_base, dtype=np.float64)
        c, s = np.cos(self.base_yaw), np.sin(self.base_yaw)
        x = c * p[..., 0] - s * p[..., 1] + self.base_xy[0]
        y = s * p[..., 0] + c * p[..., 1] + self.base_xy[1]
        z = p[..., 2] - self.table_height
        return np.stack([x, y, z], axis=-1)

    def world_to_base(self, p_world: ArrayLike) -> NDArray[np.float64]:
        """Map points (..., 3) from the world frame to the base frame [m]."""
        p = np.asarray(p_world, dtype=np.float64)
        c, s = np.cos(self.base_yaw), np.sin(self.base_yaw)
        dx, dy = p[..., 0] - self.base_xy[0], p[..., 1] - self.base_xy[1]
        return np.stack([c * dx + s * dy, -s * dx + c * dy, p[..., 2] + self.table_height], axis=-1)

    def world_transform(self) -> NDArray[np.float64]:
        """Pose of the base frame in the world frame, shape (4, 4) [m]."""
        c, s = np.cos(self.base_yaw), np.sin(self.base_yaw)
        T = np.eye(4)
        T[:2, :2] = [[c, -s], [s, c]]
        T[:3, 3] = [self.base_xy[0], self.base_xy[1], -self.table_height]
        return T
