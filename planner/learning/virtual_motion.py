"""Virtual object motions x^o (paper section III.B, Fig. 9b/9c; docs/design.md section 6).

The virtual object motion travels from the first object contact point ``q_A`` to the second,
``q_B``, while the object itself rests. Two kinds, as the paper tries:

* ``"arch"``: round the object's outline, offset outward by ``clearance * sin(pi s)`` (zero at the
  two contact points, ``clearance`` half way), the polar angle about the object's centre moving
  linearly in ``s`` the given way round; the outline's radius along each direction comes from the
  object (a disc: its radius; a convex polygon: where the ray leaves it).
* ``"line"``: the straight segment from ``q_A`` to ``q_B``.

Both are timed by the minimum-jerk profile ``s(t)`` on ``[0, T]``, so they start and end at rest,
like the demonstrated switches.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.pose import wrap_angle
from tooltransfer.validation import check_array

VirtualKind = Literal["arch", "line"]
VIRTUAL_KINDS: tuple[str, ...] = ("arch", "line")
Way = Literal["short", "ccw", "cw"]


def min_jerk(u: ArrayLike) -> NDArray[np.float64]:
    """Minimum-jerk profile ``10u^3 - 15u^4 + 6u^5`` of ``u`` in [0, 1] (clipped)."""
    v = np.clip(np.asarray(u, dtype=np.float64), 0.0, 1.0)
    return v**3 * (10.0 + v * (-15.0 + 6.0 * v))


def outline_radius(shape: Disc | shapely.Polygon, centre: NDArray[np.float64], angle: NDArray[np.float64]
                   ) -> NDArray[np.float64]:
    """Distance [m] (K,) from ``centre`` (2,) to the outline along the directions ``angle`` (K,) [rad].

    For a disc its radius; for a convex polygon containing ``centre``, where each ray leaves it.
    """
    if isinstance(shape, Disc):
        return np.full(np.shape(angle), shape.radius)
    ring = np.asarray(shape.exterior.coords, dtype=np.float64) - centre
    a, b = ring[:-1], ring[1:]
    d = np.stack([np.cos(angle), np.sin(angle)], axis=-1)  # (K, 2)
    e = b - a  # (E, 2)
    # ray t d = a + u e  ->  solve per edge; keep 0 <= u <= 1, t > 0
    den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[None, :, 0] * e[None, :, 1] - a[None, :, 1] * e[None, :, 0]) / den
        u = (a[None, :, 0] * d[:, None, 1] - a[None, :, 1] * d[:, None, 0]) / den
    ok = (np.abs(den) > 1e-15) & (u >= -1e-12) & (u <= 1 + 1e-12) & (t > 0)
    t = np.where(ok, t, np.inf)
    r = t.min(axis=1)
    if not np.all(np.isfinite(r)):
        raise InputError("centre", "a point inside the convex object", np.round(centre, 4).tolist())
    return r


def sweep_angle(q_a: NDArray[np.float64], q_b: NDArray[np.float64], centre: NDArray[np.float64],
                way: Way | float = "short") -> float:
    """Signed polar angle [rad] from ``q_a`` to ``q_b`` about ``centre``: the short way, counter-
    clockwise (``"ccw"``, > 0), clockwise (``"cw"``, < 0), or the way of the sign of a number."""
    da, db = q_a - centre, q_b - centre
    d = float(np.arctan2(db[1], db[0]) - np.arctan2(da[1], da[0]))
    short = wrap_angle(d)
    if isinstance(way, str):
        if way == "short":
            return short
        if way not in ("ccw", "cw"):
            raise InputError("way", "'short', 'ccw', 'cw' or a signed number", repr(way))
        sign = 1.0 if way == "ccw" else -1.0
    else:
        sign = 1.0 if float(way) >= 0 else -1.0
    if short * sign >= 0 and short != 0.0:
        return short
    return short + sign * 2 * np.pi if short != 0.0 else sign * 2 * np.pi


def virtual_motion(
    kind: VirtualKind,
    t: ArrayLike,
    q_a: ArrayLike,
    q_b: ArrayLike,
    shape: Disc | shapely.Polygon,
    *,
    clearance: float = 0.01,
    way: Way | float = "short",
) -> NDArray[np.float64]:
    """Virtual object motion x^o (T, 2) [m] on times ``t`` (T,) [s] (module docstring).

    Args:
        kind: ``"arch"`` or ``"line"``.
        q_a, q_b: shape (2,), first and second object contact points (world) [m].
        shape: the placed object (a :class:`~tooltransfer.tools.objects.Disc` or a convex shapely polygon); the
            arch goes round its centre (the polygon's centroid).
        clearance: the arch's largest offset from the outline [m] (>= 0).
        way: which way round the arch goes (:func:`sweep_angle`).
    """
    tt = check_array(t, "t", ndim=1)
    if tt.size < 2 or np.any(np.diff(tt) <= 0):
        raise InputError("t", "at least 2 strictly increasing times")
    qa, qb = check_array(q_a, "q_a", shape=(2,)), check_array(q_b, "q_b", shape=(2,))
    if not np.isfinite(clearance) or clearance < 0:
        raise InputError("clearance", "a finite length >= 0 [m]", repr(clearance))
    s = min_jerk((tt - tt[0]) / (tt[-1] - tt[0]))
    if kind == "line":
        return qa + s[:, None] * (qb - qa)
    if kind != "arch":
        raise InputError("kind", f"one of {', '.join(VIRTUAL_KINDS)}", repr(kind))
    if isinstance(shape, Disc):
        c = shape.centre
    elif isinstance(shape, shapely.Polygon):
        c = np.asarray(shape.centroid.coords[0])
    else:
        raise InputError("shape", "a Disc or a convex shapely Polygon", type(shape).__name__)
    dth = sweep_angle(qa, qb, c, way)
    da, db = qa - c, qb - c
    th0 = float(np.arctan2(da[1], da[0]))
    th = th0 + s * dth
    r_out = outline_radius(shape, c, th)
    # blend the contact points' own radii (they may sit slightly off the outline) into the outline's
    ra = np.hypot(*da) - outline_radius(shape, c, np.array([th0]))[0]
    rb = np.hypot(*db) - outline_radius(shape, c, np.array([th0 + dth]))[0]
    r = r_out + (1 - s) * ra + s * rb + clearance * np.sin(np.pi * s)
    return c + r[:, None] * np.stack([np.cos(th), np.sin(th)], axis=1)
