"""The Omni's reachable region on the pushing plane, and linear inner approximations for the QP.

With the waist in ``[q1_lo, q1_hi]`` and the arm-plane reach ``u`` in an interval ``[u_in, u_out]``
(from the shoulder and elbow limits at table height, computed exactly), the reachable table points
are ``b + R(base_yaw + q1) (u, d_t)``: an annular sector about the joint-1 axis ``b`` of radii
``r_in = |(u_in, d_t)|`` and ``r_out = |(u_out, d_t)|`` whose straight sides are the lines
``q1 = q1_lo`` and ``q1 = q1_hi`` (offset by ``d_t`` from the axis).

:func:`reachable_polygon` returns a polygon inside that sector (chords for the outer arc, tangents
for the inner arc) within ``tol`` of it. The ``(G, h)`` rows (``G @ p <= h`` for a world point
``p`` (2,)) of :func:`wedge_rows`, :func:`outer_rows` and :func:`inner_row` are each satisfied only
by points on the reachable side of that boundary, so their intersection is inside the region.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise
from typing import NamedTuple

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.omni.dh import D1, D_TOOL, L1
from tooltransfer.tools.omni.ik import LIMIT_ATOL, effective_link, planar_2r
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.validation import check_array, check_positive


class LinearRows(NamedTuple):
    """Half-planes ``G @ p <= h`` on a world table point ``p`` [m].

    Attributes:
        G: shape (m, 2), unit outward normals.
        h: shape (m,) [m].
    """

    G: NDArray[np.float64]
    h: NDArray[np.float64]

    def satisfied(self, points: ArrayLike, atol: float = 0.0) -> NDArray[np.bool_]:
        """Whether each point (k, 2) satisfies every row within ``atol`` [m]; shape (k,)."""
        p = np.atleast_2d(np.asarray(points, dtype=np.float64))
        return np.all(p @ self.G.T <= self.h + atol, axis=1)


@dataclass(frozen=True)
class ReachSector:
    """Exact description of the reachable table region.

    Attributes:
        centre: shape (2,), world position of the joint-1 axis [m].
        q1_range: waist range ``(lo, hi)`` [rad].
        u_range: arm-plane reach ``(u_in, u_out)`` [m].
        r_in, r_out: inner and outer radii about ``centre`` [m].
        base_yaw: the platform's base yaw [rad].
    """

    centre: NDArray[np.float64]
    q1_range: tuple[float, float]
    u_range: tuple[float, float]
    r_in: float
    r_out: float
    base_yaw: float

    def point(
        self, q1: float | NDArray[np.float64], u: float | NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """World point(s) (..., 2) [m] reached with waist ``q1`` [rad] and arm-plane reach ``u``."""
        a = self.base_yaw + np.asarray(q1, dtype=np.float64)
        u = np.asarray(u, dtype=np.float64)
        x = np.cos(a) * u - np.sin(a) * D_TOOL + self.centre[0]
        y = np.sin(a) * u + np.cos(a) * D_TOOL + self.centre[1]
        return np.stack([x, y], axis=-1)


def _feasible_u(platform: OmniPlatform, u: float, v: float) -> bool:
    lo, hi = platform.limits.lower, platform.limits.upper
    for q2, q3 in planar_2r(u, v, platform.a_t):
        if (
            lo[1] - LIMIT_ATOL <= q2 <= hi[1] + LIMIT_ATOL
            and lo[2] - LIMIT_ATOL <= q3 <= hi[2] + LIMIT_ATOL
        ):
            return True
    return False


def reach_intervals(platform: OmniPlatform) -> list[tuple[float, float]]:
    """Intervals of arm-plane reach ``u`` [m] (signed) attainable at table height within limits.

    Exact up to rounding: feasibility can change only where the 2R arm hits its reach annulus or
    a shoulder or elbow limit, all of which have closed-form ``u``; between consecutive candidates
    feasibility is constant and is tested at the midpoint.
    """
    v = D1 - platform.table_height
    le, delta = effective_link(platform.a_t)
    radii = [L1 + le, abs(L1 - le)]
    radii += [
        float(abs(L1 + le * np.exp(1j * (q3 + delta))))
        for q3 in (platform.limits.lower[2], platform.limits.upper[2])
    ]
    cands: list[float] = []
    for r in radii:
        if r >= abs(v):
            w = float(np.sqrt(r * r - v * v))
            cands += [w, -w]
    for q2 in (platform.limits.lower[1], platform.limits.upper[1]):
        ex, ey = L1 * np.cos(q2), L1 * np.sin(q2)
        if le >= abs(v - ey):
            w = float(np.sqrt(le * le - (v - ey) ** 2))
            cands += [ex + w, ex - w]
    cands = sorted(set(cands))
    intervals: list[tuple[float, float]] = []
    for a, b in pairwise(cands):
        if b - a > 1e-12 and _feasible_u(platform, 0.5 * (a + b), v):
            if intervals and abs(intervals[-1][1] - a) <= 1e-12:
                intervals[-1] = (intervals[-1][0], b)
            else:
                intervals.append((a, b))
    return intervals


def reach_sector(platform: OmniPlatform) -> ReachSector:
    """The reachable table region of ``platform`` as an exact annular sector.

    Raises:
        InputError: the limits give no reach at table height, a reach that is not one interval of
            positive ``u`` (the arm reaching behind its shoulder), or a waist range of pi or more.
    """
    intervals = reach_intervals(platform)
    if not intervals:
        raise InputError(
            "platform.table_height",
            "a height the arm reaches within its limits",
            repr(platform.table_height),
        )
    if len(intervals) != 1 or intervals[0][0] <= 0.0:
        raise InputError(
            "platform.limits",
            "limits giving one forward (u > 0) reach interval",
            f"intervals {intervals}",
        )
    q1_lo, q1_hi = platform.limits.lower[0], platform.limits.upper[0]
    if q1_hi - q1_lo >= np.pi:
        raise InputError("platform.limits", "a waist range shorter than pi rad", f"{q1_hi - q1_lo}")
    u_in, u_out = intervals[0]
    return ReachSector(
        centre=np.array(platform.base_xy, dtype=np.float64),
        q1_range=(q1_lo, q1_hi),
        u_range=(u_in, u_out),
        r_in=float(np.hypot(u_in, D_TOOL)),
        r_out=float(np.hypot(u_out, D_TOOL)),
        base_yaw=platform.base_yaw,
    )


def _n_arc(radius: float, span: float, tol: float) -> int:
    """Pieces so that chords (tangents) of an arc stay within ``tol`` [m] of it."""
    half = float(np.arccos(radius / (radius + tol)))  # tangent overshoot r(1/cos - 1) = tol
    return max(1, int(np.ceil(span / (2.0 * half))))


def reachable_polygon(platform: OmniPlatform, tol: float = 1e-4) -> shapely.Polygon:
    """Polygon [m] inside the reachable table region, within Hausdorff distance ``tol`` [m] of it.

    Sides are exact; the outer arc is replaced by chords (inside it) and the inner arc by tangent
    segments (outside the inner circle), each deviating from the arc by at most ``tol``.
    """
    tol = check_positive(tol, "tol")
    sec = reach_sector(platform)
    (q1_lo, q1_hi), (u_in, u_out) = sec.q1_range, sec.u_range
    g_out = float(np.arctan2(D_TOOL, u_out))
    g_in = float(np.arctan2(D_TOOL, u_in))
    span = q1_hi - q1_lo
    a0 = sec.base_yaw + q1_lo
    n_out = _n_arc(sec.r_out, span, tol)
    phi = a0 + g_out + np.linspace(0.0, span, n_out + 1)
    outer = sec.centre + sec.r_out * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    n_in = _n_arc(sec.r_in, span, tol)
    phi_in = a0 + g_in + np.linspace(span, 0.0, n_in + 1)
    half = 0.5 * span / n_in
    mids = 0.5 * (phi_in[:-1] + phi_in[1:])
    tangent = sec.centre + (sec.r_in / np.cos(half)) * np.stack(
        [np.cos(mids), np.sin(mids)], axis=1
    )
    inner = np.vstack([sec.point(q1_hi, u_in)[None], tangent, sec.point(q1_lo, u_in)[None]])
    ring = np.vstack([outer, inner])
    poly = shapely.Polygon(ring)
    if not poly.is_valid:  # pragma: no cover - guarded by reach_sector's checks
        raise InputError(
            "platform", "a reachable region that is a simple polygon", shapely.is_valid_reason(poly)
        )
    return poly


def wedge_rows(platform: OmniPlatform) -> LinearRows:
    """Two exact half-planes bounding the waist range: the lines ``q1 = q1_lo`` and ``q1 = q1_hi``.

    Returns:
        rows (2, 2) / (2,): a point satisfies them iff its forward-branch waist angle is in range
        (for points outside the inner radius).
    """
    sec = reach_sector(platform)
    G, h = [], []
    for q1, sign in ((sec.q1_range[0], -1.0), (sec.q1_range[1], 1.0)):
        a = sec.base_yaw + q1
        n = np.array([-np.sin(a), np.cos(a)])  # direction of increasing q1 at the line
        G.append(sign * n)
        h.append(sign * (D_TOOL + n @ sec.centre))
    return LinearRows(np.array(G), np.array(h))


def outer_rows(platform: OmniPlatform, tol: float = 1e-4) -> LinearRows:
    """Chord half-planes: with :func:`wedge_rows` they keep points inside the outer radius.

    The chords of the circle ``r_out`` cover every direction a point of the wedge beyond ``r_out``
    can have, so wedge plus chords is a convex polygon inside the outer disc, within ``tol`` [m].
    """
    tol = check_positive(tol, "tol")
    sec = reach_sector(platform)
    g_out = float(np.arctan2(D_TOOL, sec.u_range[1]))
    lo = sec.base_yaw + sec.q1_range[0]
    hi = sec.base_yaw + sec.q1_range[1] + g_out
    n = _n_arc(sec.r_out, hi - lo, tol)
    edges = np.linspace(lo, hi, n + 1)
    mids = 0.5 * (edges[:-1] + edges[1:])
    G = np.stack([np.cos(mids), np.sin(mids)], axis=1)
    h = sec.r_out * np.cos(0.5 * (hi - lo) / n) + G @ sec.centre
    return LinearRows(G, h)


def inner_row(platform: OmniPlatform, at: ArrayLike) -> LinearRows:
    """Tangent half-plane of the inner reach circle, linearized at the world point ``at`` (2,) [m].

    The row ``-n . (p - b) <= -r_in`` with ``n`` the unit direction from the axis ``b`` to ``at``
    keeps points outside the inner radius (a convex inner approximation of the non-convex set).
    """
    p0 = check_array(at, "at", shape=(2,))
    sec = reach_sector(platform)
    d = p0 - sec.centre
    norm = float(np.hypot(*d))
    if norm < 1e-12:
        raise InputError("at", "a point away from the joint-1 axis", "the axis itself")
    n = d / norm
    return LinearRows(-n[None, :], np.array([-sec.r_in - n @ sec.centre]))


def stack_rows(*rows: LinearRows) -> LinearRows:
    """Concatenate several row sets into one ``(G, h)``."""
    return LinearRows(np.vstack([r.G for r in rows]), np.concatenate([r.h for r in rows]))
