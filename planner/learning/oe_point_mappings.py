"""The OE mappings (paper eq. (7)) applied to points: move them radially about reference points.

Inner (7) pulls points into a ball or a tube of radius ``r_b`` about their centres; the monotone outer (7)
pushes them out of an obstacle's disc of radius ``r_b + delta``. Points have shape (..., d), centres broadcast
to them; the radial maps are those of :mod:`tooltransfer.planner.learning.oe_mappings` and
:mod:`tooltransfer.planner.learning.oe_outer_mappings`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.oe_map_parameters import check_k, check_radius
from tooltransfer.planner.learning.oe_mappings import clip_open_upper, saturate, saturate_inverse
from tooltransfer.planner.learning.oe_outer_mappings import outer_excess, outer_radius_inverse, outer_sum
from tooltransfer.validation import check_array

__all__ = ["inner_inverse_points", "inner_map_points", "outer_inverse_points", "outer_map_points"]


def _offsets(
    x: ArrayLike, center: ArrayLike, xf: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Return ``(c, r, u)``: broadcast centres (..., d), radii (...) and unit directions (..., d) (0 at the centre)."""
    xa = check_array(x, xf)
    ca = check_array(center, "center")
    if xa.ndim < 1 or ca.ndim < 1:
        raise InputError(xf if xa.ndim < 1 else "center", "points of shape (..., d)", "a scalar")
    try:
        xa, ca = np.broadcast_arrays(xa, ca)
    except ValueError as exc:
        raise InputError("center", f"a shape broadcastable to {xf}'s {xa.shape}", f"{ca.shape}") from exc
    with np.errstate(over="ignore"):
        d = xa - ca
    if not np.all(np.isfinite(d)):
        raise InputError(xf, "points whose offsets from the centre are finite")
    m = np.max(np.abs(d), axis=-1, keepdims=True)  # scale first: no under/overflow in the squares
    s = d / np.where(m > 0.0, m, 1.0)
    n = np.sqrt(np.sum(s * s, axis=-1, keepdims=True))
    with np.errstate(over="ignore"):
        r = (m * n)[..., 0]
    if not np.all(np.isfinite(r)):
        raise InputError(xf, "points whose distances from the centre are finite")
    u = s / np.where(n > 0.0, n, 1.0)
    return ca, r, u


def inner_map_points(x_p: ArrayLike, center: ArrayLike, r_b: float, k: float) -> NDArray[np.float64]:
    """Inner (7) applied to points: ``x_g = x_o + r_g(|x_p - x_o|) (x_p - x_o) / |x_p - x_o|``.

    Args:
        x_p: Universal points [m], shape (..., d).
        center: Reference points ``x_o`` [m], broadcastable to ``x_p`` (e.g. (d,) for a ball, or the
            universal path's samples (T, d) for a tube of radius ``r_b`` around it).
        r_b: Radius [m] of the ball or tube, in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).

    Returns:
        Condensed points [m], the broadcast shape (..., d), each strictly within ``r_b`` of its centre.
    """
    rb = check_radius(r_b, "r_b")
    kk = check_k(k)
    c, r, u = _offsets(x_p, center, "x_p")
    return c + u * saturate(r, rb, kk)[..., None]


def inner_inverse_points(
    x_g: ArrayLike, center: ArrayLike, r_b: float, k: float, *, clip: bool = False
) -> NDArray[np.float64]:
    """Exact inverse of :func:`inner_map_points`; ``clip`` as in
    :func:`~tooltransfer.planner.learning.oe_mappings.inner_radius_inverse`.

    Args:
        x_g: Condensed points [m], shape (..., d), strictly within ``r_b`` of their centres.
        center: Reference points [m], broadcastable to ``x_g``.
        r_b: Radius [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).
        clip: Points at distance ``>= r_b`` raise :class:`InputError` (False) or are pulled radially to the
            largest double below ``r_b`` (True).

    Returns:
        Universal points [m], the broadcast shape (..., d).
    """
    rb = check_radius(r_b, "r_b")
    kk = check_k(k)
    c, r, u = _offsets(x_g, center, "x_g")
    r = clip_open_upper(r, rb, "x_g", clip)
    return c + u * saturate_inverse(r, rb, kk, "x_g")[..., None]


def outer_map_points(
    x_p: ArrayLike, center: ArrayLike, r_b: float, k: float, *, delta: float = 0.0
) -> NDArray[np.float64]:
    """Monotone outer (7) applied to points: pushes them out of the disc of radius ``r_b + delta``.

    Args:
        x_p: Universal points [m], shape (..., d), none at its centre (the centre's image direction is
            undefined).
        center: Obstacle centres ``x_o`` [m], broadcastable to ``x_p``.
        r_b: Obstacle radius [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).
        delta: Safety margin [m] (section IV.E), in [0, MAX_RADIUS].

    Returns:
        Condensed points [m], the broadcast shape (..., d), each at distance ``>= r_b + delta`` from its
        centre (up to the rounding of adding the offset to the centre).
    """
    R = check_radius(r_b, "r_b") + check_radius(delta, "delta", allow_zero=True)
    kk = check_k(k)
    c, r, u = _offsets(x_p, center, "x_p")
    if np.any(r == 0.0):
        raise InputError("x_p", "points distinct from the centre (its outer-space image direction is undefined)")
    return c + u * outer_sum(R, outer_excess(r, R, kk), "x_p")[..., None]


def outer_inverse_points(
    x_g: ArrayLike, center: ArrayLike, r_b: float, k: float, *, delta: float = 0.0, clip: bool = False
) -> NDArray[np.float64]:
    """Exact inverse of :func:`outer_map_points`; ``clip`` as in :func:`outer_radius_inverse`.

    Args:
        x_g: Condensed points [m], shape (..., d), at distance ``>= r_b + delta`` from their centres.
        center: Obstacle centres [m], broadcastable to ``x_g``.
        r_b: Obstacle radius [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).
        delta: Safety margin [m], in [0, MAX_RADIUS].
        clip: Points closer than ``r_b + delta`` raise :class:`InputError` (False) or map to the centre (True).

    Returns:
        Universal points [m], the broadcast shape (..., d).
    """
    c, r, u = _offsets(x_g, center, "x_g")
    try:
        rp = outer_radius_inverse(r, r_b, k, delta=delta, clip=clip)
    except InputError as exc:
        raise InputError("x_g", exc.expected, exc.got) from exc
    return c + u * rp[..., None]
