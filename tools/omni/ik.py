"""Closed-form inverse kinematics of the Omni for a tool centre point on the pushing plane.

The tool centre point is ``p = o1 + u x1 + v y1 + d_t z1`` (see :mod:`tooltransfer.tools.omni.dh`): in the base
frame its horizontal part is ``R(q1) (u, d_t)`` and its height ``d1 - v``. Given a table point:

1. ``u = +-sqrt(rho^2 - d_t^2)`` with ``rho`` its horizontal distance from the joint-1 axis, and
   ``q1 = atan2(y_b, x_b) - atan2(d_t, u)`` (two waist branches);
2. joints 2, 3 and the rigid forearm-plus-tool link form a planar 2R arm with lengths ``L1`` and
   ``L_e = |L2 + a_t exp(i 2pi/3)|`` (link angle offset ``delta = arg(...)``) reaching ``(u, v)``
   (two elbow branches).

All four branches are returned with the joints they violate; the chosen one is inside the limits
(closest to a reference configuration when given). Unreachable targets give a result with
``reachable = False`` and a reason, never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.tools.omni.dh import D1, D_TOOL, L1, L2, THETA_TOOL, forward_kinematics
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import wrap_angle
from tooltransfer.validation import check_array

Reason = Literal["radius", "angle", "joint limit"]

#: Tolerance [rad] on joint limits, so points on the boundary of the reachable polygon count.
LIMIT_ATOL = 1e-9


def effective_link(a_t: float) -> tuple[float, float]:
    """Length [m] and angle offset ``delta`` [rad] of the rigid forearm-plus-tool link."""
    w = L2 + a_t * np.exp(1j * THETA_TOOL)
    return float(abs(w)), float(np.angle(w))


@dataclass(frozen=True)
class IKBranch:
    """One closed-form solution: ``q`` (3,) [rad] and the 0-based joints outside the limits."""

    q: NDArray[np.float64]
    violated: tuple[int, ...]

    @property
    def within_limits(self) -> bool:
        """True when no joint is outside its limits."""
        return not self.violated


@dataclass(frozen=True)
class IKResult:
    """Outcome of :func:`inverse_kinematics`.

    Attributes:
        reachable: True when a branch inside the joint limits exists.
        q: shape (3,), the chosen joint angles [rad], or None when unreachable.
        heading: yaw of the planar tool frame in the world [rad] for ``q``, or None.
        reason: why the target is unreachable (``"radius"``: no arm configuration reaches that
            distance; ``"angle"``: the waist would leave its range; ``"joint limit"``: only
            configurations with the shoulder or elbow outside its range reach it), else None.
        detail: a sentence with the numbers behind ``reason``.
        branches: every closed-form solution (0, 2 or 4), inside the limits or not.
    """

    reachable: bool
    q: NDArray[np.float64] | None
    heading: float | None
    reason: Reason | None
    detail: str
    branches: tuple[IKBranch, ...]


def planar_2r(u: float, v: float, a_t: float) -> list[tuple[float, float]]:
    """Solutions ``(q2, q3)`` [rad] placing the tool centre point at ``(u, v)`` in the arm plane.

    ``u`` is horizontal along the arm and ``v`` downward from the shoulder [m]. Returns 0 or 2
    solutions (1 repeated at the boundary of the reach annulus).
    """
    le, delta = effective_link(a_t)
    c = (u * u + v * v - L1 * L1 - le * le) / (2.0 * L1 * le)
    if abs(c) > 1.0 + 1e-12:
        return []
    c = min(1.0, max(-1.0, c))
    out = []
    for sign in (1.0, -1.0):
        q3p = sign * float(np.arccos(c))
        q2 = np.arctan2(v, u) - np.arctan2(le * np.sin(q3p), L1 + le * np.cos(q3p))
        out.append((wrap_angle(q2), wrap_angle(q3p - delta)))
    return out


def inverse_kinematics(
    platform: OmniPlatform, point: ArrayLike, q_ref: ArrayLike | None = None
) -> IKResult:
    """Joint angles placing the tool centre point at a world point on the pushing plane.

    Args:
        platform: the Omni's placement, limits and tool length.
        point: shape (2,), world table point ``(x, y)`` [m].
        q_ref: shape (3,) [rad], optional; among valid branches the closest to it is chosen,
            otherwise the first valid one (arm pointing at the target, elbow up).
    """
    p = check_array(point, "point", shape=(2,))
    ref = None if q_ref is None else check_array(q_ref, "q_ref", shape=(3,))
    bx, by, _ = platform.world_to_base([p[0], p[1], 0.0])
    rho = float(np.hypot(bx, by))
    v = D1 - platform.table_height
    if rho < D_TOOL:
        return IKResult(
            False,
            None,
            None,
            "radius",
            f"point is {rho:.6g} m from the joint-1 axis, inside the tool offset d_t = {D_TOOL} m",
            (),
        )
    u_abs = float(np.sqrt(max(rho * rho - D_TOOL * D_TOOL, 0.0)))
    branches: list[IKBranch] = []
    for u in (u_abs, -u_abs):
        q1 = wrap_angle(np.arctan2(by, bx) - np.arctan2(D_TOOL, u))
        for q2, q3 in planar_2r(u, v, platform.a_t):
            q = np.array([q1, q2, q3])
            branches.append(IKBranch(q, platform.limits.violated(q, LIMIT_ATOL)))
    if not branches:
        le, _ = effective_link(platform.a_t)
        dist = float(np.hypot(u_abs, v))
        return IKResult(
            False,
            None,
            None,
            "radius",
            f"shoulder-to-point distance {dist:.6g} m outside the arm's annulus "
            f"[{abs(L1 - le):.6g}, {L1 + le:.6g}] m",
            (),
        )
    valid = [b for b in branches if b.within_limits]
    if not valid:
        if all(0 in b.violated for b in branches):
            q1s = ", ".join(f"{b.q[0]:.4g}" for b in branches[::2])
            reason: Reason = "angle"
            detail = (
                f"waist angle q1 in {{{q1s}}} rad outside "
                f"[{platform.limits.lower[0]}, {platform.limits.upper[0]}] rad"
            )
        else:
            reason = "joint limit"
            parts = [
                f"q={np.round(b.q, 4).tolist()} violates joint(s) {[j + 1 for j in b.violated]}"
                for b in branches
            ]
            detail = "; ".join(parts)
        return IKResult(False, None, None, reason, detail, tuple(branches))
    if ref is not None:
        best = min(valid, key=lambda b: float(np.linalg.norm(b.q - ref)))
    else:
        best = valid[0]
    return IKResult(
        True, best.q.copy(), float(platform.heading(best.q[0])), None, "", tuple(branches)
    )


def tool_pose_world(platform: OmniPlatform, q: ArrayLike) -> NDArray[np.float64]:
    """Pose of the DH tool frame in the world frame, shape (4, 4) [m], for joints ``q`` (3,)."""
    qv = check_array(q, "q", shape=(3,))
    return platform.world_transform() @ forward_kinematics(qv, platform.a_t)


def table_pose(platform: OmniPlatform, q: ArrayLike) -> tuple[float, float, float]:
    """Planar tool pose ``(x, y, heading)`` [m, m, rad] in the world for joints ``q`` (3,).

    ``(x, y)`` is the tool centre point projected on the table; the heading follows ``q1``.
    """
    T = tool_pose_world(platform, q)
    qv = np.asarray(q, dtype=np.float64)
    return float(T[0, 3]), float(T[1, 3]), float(platform.heading(qv[0]))


@dataclass(frozen=True)
class JointPath:
    """Joints along a tool path, from :func:`joint_path`.

    Attributes:
        q: shape (T, 3) [rad]; NaN rows where no arm configuration reaches the point at all.
        violation: shape (T,) [rad], how far the chosen branch is outside the joint limits (0 when
            inside, inf where unreachable at any joint values).
        heading: shape (T,) [rad], the tool yaw the waist imposes (NaN where unreachable).
    """

    q: NDArray[np.float64]
    violation: NDArray[np.float64]
    heading: NDArray[np.float64]

    @property
    def refused(self) -> NDArray[np.bool_]:
        """Shape (T,): the samples the Omni cannot take, out of its reach (no heading) or with the
        chosen branch outside the joint limits; a path is executable where none is set."""
        return ~np.isfinite(self.heading) | (self.violation > 0)


def joint_path(platform: OmniPlatform, points: ArrayLike) -> JointPath:
    """Vectorized inverse kinematics along a tool path ``points`` (T, 2) [m] on the pushing plane.

    One branch for the whole path: the forward waist branch (``u > 0``) with the elbow branch that
    stays inside the limits at the most samples (ties: elbow up, the first of
    :func:`inverse_kinematics`), so joints vary continuously along a continuous path. Where that
    branch leaves the limits the joints are kept and ``violation`` says by how much.
    """
    p = check_array(points, "points", shape=(None, 2))
    b = platform.world_to_base(np.column_stack([p, np.zeros(len(p))]))
    rho = np.hypot(b[:, 0], b[:, 1])
    v = D1 - platform.table_height
    u = np.sqrt(np.maximum(rho**2 - D_TOOL**2, 0.0))
    q1 = np.arctan2(b[:, 1], b[:, 0]) - np.arctan2(D_TOOL, u)
    q1 = wrap_angle(q1)
    le, delta = effective_link(platform.a_t)
    c = (u * u + v * v - L1 * L1 - le * le) / (2.0 * L1 * le)
    ok = (np.abs(c) <= 1.0 + 1e-12) & (rho >= D_TOOL)
    c = np.clip(c, -1.0, 1.0)
    lo, hi = np.asarray(platform.limits.lower), np.asarray(platform.limits.upper)
    best: tuple[int, NDArray[np.float64], NDArray[np.float64]] | None = None
    for sign in (1.0, -1.0):
        q3p = sign * np.arccos(c)
        q2 = np.arctan2(v, u) - np.arctan2(le * np.sin(q3p), L1 + le * np.cos(q3p))
        q = np.column_stack([q1, wrap_angle(q2), wrap_angle(q3p - delta)])
        excess = np.maximum(np.maximum(lo - q, q - hi), 0.0).max(axis=1)
        excess[excess <= LIMIT_ATOL] = 0.0
        score = int(np.sum(ok & (excess == 0.0)))
        if best is None or score > best[0]:
            best = (score, q, excess)
    assert best is not None  # two elbow branches were tried
    _, q, excess = best
    q[~ok] = np.nan
    excess[~ok] = np.inf
    heading = np.where(ok, platform.heading(q[:, 0]), np.nan)
    return JointPath(q, excess, heading)
