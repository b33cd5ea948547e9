"""Paper eqs. (6)-(8): exponential maps between the universal space and a tool's condensed space.

The OE skill is learned in the *universal space* (free of tool 1's pushing limits) and condensed
into the *constrained space* of a tool or an environment by two saturating maps (docs/design.md section 5):

- **Angle map, eq. (6).** ``theta_g`` [rad] is a step direction measured from the active face's push
  direction (any real, e.g. ``wrap_angle(phi - phi_face)``); ``theta`` [rad] is the condensed
  direction inside the face's cone ``(-theta_b, theta_b)``::

      theta = sign(theta_g) * theta_b * (1 - exp(-k |theta_g| / theta_b))

  exact inverse ``|theta_g| = -(theta_b / k) * ln(1 - |theta| / theta_b)``.
- **Inner space, eq. (7) lower line.** A radius ``r_p`` [m] about a reference point ``x_o`` (e.g. the
  universal path's sample, giving a tube) goes into ``[0, r_b)``::

      r_g = r_b * (1 - exp(-k r_p / r_b)),        inverse  r_p = -(r_b / k) * ln(1 - r_g / r_b)

- **Outer space, monotone form (docs/design.md section 5).** Keeps points outside a disc of radius ``R`` about
  ``x_o`` (an obstacle), identity far away (the paper's "tail effect")::

      r_g = r_p + R * exp(-k r_p / R),            R = r_b + delta

  strictly increasing for ``k`` in (0, 1) because ``dr_g/dr_p = 1 - k exp(-k r_p / R) >= 1 - k > 0``;
  image ``[R, inf)``, reached at ``r_p = 0``. Exact inverse with the principal branch ``W_0`` of the
  Lambert W function::

      r_p = r_g + (R / k) * W_0(-k * exp(-k r_g / R))

  (substitute ``z = r_g - r_p = R exp(-k r_p / R)``: ``(-k z / R) exp(-k z / R) = -k exp(-k r_g / R)``,
  and ``-k z / R`` lies in ``[-k, 0)``, inside ``W_0``'s range ``[-1, 0)``). ``delta >= 0`` [m] is the
  safety margin of the paper's section IV.E, applied as ``r_b -> r_b + delta`` (docs/design.md section 9:
  the paper's text says "changing r_g to r_g + delta", but adding delta to the image alone would also
  shift far points and lose the identity tail).
- **Outer space as printed in (7)** (``outer_radius_printed``), kept for comparison only:
  ``r_g = r_b + r_b * exp(-k r_p / r_b)`` maps ``[0, inf)`` onto ``(r_b, 2 r_b]`` but is strictly
  *decreasing*: the reference point ``r_p = 0`` goes to ``2 r_b`` and far points come to ``r_b``, so it
  reverses the order of radii and turns a path inside out around the obstacle (docs/design.md section 9).

The paper's eq. (8), ``|theta_g| = k +- sqrt(0.25 theta_b^2 - theta theta_b) / k``, is a second-order
Taylor inverse with four roots; it is not implemented, the exact inverses above are.

Parameters shared by every function: ``k`` in the open interval (0, 1) (the paper's adjusting factor,
dimensionless), ``theta_b`` in (0, pi/2] [rad] (a cone no wider than a half-plane; the paper gives no range),
``r_b`` in (0, MAX_RADIUS] [m], ``delta`` in [0, MAX_RADIUS] [m]. ``k``, ``theta_b`` and ``r_b`` must be
normal doubles (>= 2.2e-308): a subnormal bound leaves no room for the image. Inputs must be finite; radii
must be >= 0. Invalid parameters or inputs raise :class:`tooltransfer.errors.InputError` naming the argument; there
is no ``assert`` on user input.

Numerics. All radial and angle maps are vectorized: an array of any shape in, float64 array of the same
shape out. The forward maps use ``expm1`` and the inverses ``log1p`` (or ``log`` of the exactly computed
distance to the bound, ``r_b - r_g``, when that is the accurate one), so values near zero keep full
relative accuracy and values near the bound keep full absolute accuracy. A saturating map's image is
open at the bound, but ``1 - exp(-u)`` rounds to 1 for ``u > 37``; the forward maps therefore return the
largest double strictly inside the bound instead (an error of at most one unit in the last place), so
every image is strictly inside its bound for every finite input, including 1e300.

Accuracy. Each forward map and each inverse is accurate to a few ulps (tested at 1e-15 relative against
60-digit references for ``theta_b >= 1e-6`` rad, ``1e-9 <= r_b <= 1e3`` m, ``k >= 1e-6``; for bounds near
the underflow threshold intermediate values turn subnormal and lose significant bits). The Lambert-W
closed form alone is only accurate to about ``sqrt(eps)`` near ``W_0``'s branch point (``k`` near 1, ``r_g``
near ``R``) and cancels in ``r_g + (R/k) W``;
:func:`~tooltransfer.planner.learning.oe_outer_mappings.outer_radius_inverse` therefore polishes it with Newton
steps on the cancellation-free excess ``r_g - R = r_p (1 - k) + R (exp(-u) - 1 + u)``.

Round-trip accuracy (universal -> condensed -> universal) is limited by the rounding of the condensed
value, not by these formulas: its relative error is about ``eps * kappa`` with the condition number
``kappa = (e^u - 1) / u``, ``u = k x / bound``, for (6) and inner (7), and
``kappa = r_g / (r_p (1 - k exp(-k r_p / R)))`` for outer (7), which grows without limit as ``r_p -> 0``
(``r_g -> R``: the small excess ``r_g - R`` is stored next to the large ``R``). Where ``kappa`` is large
the inverses are backward stable instead: ``forward(inverse(y))`` reproduces ``y`` to a few ulps. Near zero
the angle and inner maps keep full relative accuracy (slope ``k`` at 0) down to the underflow threshold;
subnormal values carry an absolute error of one subnormal spacing.

Monotonicity. (6), inner (7), their inverses and the printed outer form are computed as compositions of
monotone operations, so they are monotone in floating point too (non-decreasing; non-increasing for the
printed form), and strictly so wherever the exact difference is larger than a few ulps. The monotone outer
map is a sum of an increasing and a decreasing part and its inverse is Newton-polished: between consecutive
doubles they may step back by one ulp (never more; tested), because their slope can be below one.

Inverting a value on or beyond the image bound is an error unless the caller asks for clipping with
``clip=True``: it then replaces the value by the nearest value inside the image, namely the largest
double strictly inside an open bound (``(1 - eps) * bound`` with ``eps`` one unit in the last place,
about 1.1e-16 relative, so that clipping keeps the inverse monotone) or the bound itself when the image
is closed there (``R`` for the monotone outer map, ``2 r_b`` for the printed one).

Where the maps live: this module holds eq. (6), inner (7) and the saturating core they share; the outer
maps are in :mod:`tooltransfer.planner.learning.oe_outer_mappings`, the maps of points in
:mod:`tooltransfer.planner.learning.oe_point_mappings`, and the parameter domains with their checks in
:mod:`tooltransfer.planner.learning.oe_map_parameters`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.oe_map_parameters import (
    TINY,
    check_k,
    check_radii,
    check_radius,
    check_theta_b,
    first_bad,
)
from tooltransfer.tools.pose import wrap_angle as _wrap_unchecked
from tooltransfer.validation import check_array

__all__ = [
    "angle_inverse",
    "angle_map",
    "inner_radius",
    "inner_radius_inverse",
    "wrap_angle",
]


# --------------------------------------------------------------------------------------------------
# the saturating core shared by (6) and inner (7): y = b (1 - exp(-k x / b)), x >= 0, y in [0, b)


def ratio(k: float, x: NDArray[np.float64], b: float) -> NDArray[np.float64]:
    """``u = k x / b >= 0`` without spurious overflow (``x / b`` may overflow where ``k x / b`` does not)."""
    with np.errstate(over="ignore"):  # an infinite u is the right limit: the maps saturate
        q = x / b
        return np.where(np.isinf(q), (k * x) / b, k * q)  # k normal: k x is normal whenever x / b overflows


def saturate(x: NDArray[np.float64], b: float, k: float) -> NDArray[np.float64]:
    """``b (1 - exp(-k x / b))`` for ``x >= 0``, strictly below ``b``; same shape as ``x``."""
    u = ratio(k, x, b)
    y = -b * np.expm1(-u)
    # u subnormal or zero: b * u loses relative precision; exp(-u) - 1 = -u exactly there.
    y = np.where(u < TINY, k * x, y)
    return np.minimum(y, np.nextafter(b, 0.0))


def saturate_inverse(y: NDArray[np.float64], b: float, k: float, field: str) -> NDArray[np.float64]:
    """``-(b / k) ln(1 - y / b)`` for ``0 <= y < b``; same shape as ``y``."""
    t = y / b
    near = t > 0.5
    # ln(1 - t): log1p for t <= 1/2; for t > 1/2 the distance b - y is exact (Sterbenz), use log of it.
    lg_small = -np.log1p(-np.minimum(t, 0.5))
    lg_near = -np.log(np.where(near, (b - y) / b, 0.5))
    lg = np.where(near, lg_near, lg_small)
    with np.errstate(over="ignore"):
        x = (lg * b) / k
        x = np.where(t < TINY, y / k, x)  # t subnormal or zero: ln(1 - t) = -t exactly, keep y's precision
    if not np.all(np.isfinite(x)):
        raise InputError(field, f"values whose preimage is representable for k = {k!r} (it overflows)")
    return x


def clip_open_upper(y: NDArray[np.float64], b: float, field: str, clip: bool) -> NDArray[np.float64]:
    """Enforce ``y < b`` for an image open at ``b``: clip to the largest double below ``b`` or raise."""
    beyond = y >= b
    if np.any(beyond):
        if not clip:
            raise InputError(
                field, f"values strictly inside the image bound {b!r} (pass clip=True to clip)", first_bad(beyond, y)
            )
        y = np.where(beyond, np.nextafter(b, 0.0), y)
    return y


# --------------------------------------------------------------------------------------------------
# eq. (6): angles


def wrap_angle(angle: ArrayLike) -> NDArray[np.float64]:
    """Wrap finite angles [rad] of any shape into ``[-pi, pi)``, e.g. a direction relative to a push
    direction: :func:`tooltransfer.tools.pose.wrap_angle` behind the check of the input.

    Raises:
        InputError: ``angle`` not an array of finite reals.
    """
    return _wrap_unchecked(check_array(angle, "angle"))


def angle_map(theta_g: ArrayLike, theta_b: float, k: float) -> NDArray[np.float64]:
    """Eq. (6): condense a universal angle into the cone ``(-theta_b, theta_b)``.

    ``theta = sign(theta_g) * theta_b * (1 - exp(-k |theta_g| / theta_b))``, odd and strictly increasing.

    Args:
        theta_g: Universal angles [rad] relative to the face's push direction, any finite reals, any shape.
        theta_b: Cone half-angle [rad], in (0, pi/2].
        k: Adjusting factor in (0, 1); the slope at 0 is ``k``.

    Returns:
        Condensed angles ``theta`` [rad], same shape as ``theta_g``, with ``|theta| < theta_b`` always.
    """
    tb = check_theta_b(theta_b)
    kk = check_k(k)
    tg = check_array(theta_g, "theta_g")
    return np.copysign(saturate(np.abs(tg), tb, kk), tg)


def angle_inverse(theta: ArrayLike, theta_b: float, k: float, *, clip: bool = False) -> NDArray[np.float64]:
    """Exact inverse of eq. (6): ``|theta_g| = -(theta_b / k) * ln(1 - |theta| / theta_b)``.

    Args:
        theta: Condensed angles [rad], any shape, ``|theta| < theta_b``.
        theta_b: Cone half-angle [rad], in (0, pi/2].
        k: Adjusting factor in (0, 1).
        clip: If False (default), ``|theta| >= theta_b`` raises :class:`InputError`; if True such values
            are clipped to the largest double below ``theta_b`` (same sign), whose preimage is about
            ``36.7 theta_b / k``.

    Returns:
        Universal angles ``theta_g`` [rad], same shape as ``theta``.
    """
    tb = check_theta_b(theta_b)
    kk = check_k(k)
    th = check_array(theta, "theta")
    a = clip_open_upper(np.abs(th), tb, "theta", clip)
    return np.copysign(saturate_inverse(a, tb, kk, "theta"), th)


# --------------------------------------------------------------------------------------------------
# eq. (7), inner space


def inner_radius(r_p: ArrayLike, r_b: float, k: float) -> NDArray[np.float64]:
    """Eq. (7), inner space: ``r_g = r_b * (1 - exp(-k r_p / r_b))``, strictly increasing.

    Args:
        r_p: Universal radii [m] about the reference point, ``>= 0``, any shape.
        r_b: Radius of the admissible ball or tube [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).

    Returns:
        Condensed radii ``r_g`` [m], same shape, with ``0 <= r_g < r_b`` always (``r_g = 0`` iff ``r_p = 0``
        up to underflow).
    """
    rb = check_radius(r_b, "r_b")
    kk = check_k(k)
    rp = check_radii(r_p, "r_p")
    return saturate(rp, rb, kk)


def inner_radius_inverse(r_g: ArrayLike, r_b: float, k: float, *, clip: bool = False) -> NDArray[np.float64]:
    """Exact inverse of inner (7): ``r_p = -(r_b / k) * ln(1 - r_g / r_b)``.

    Args:
        r_g: Condensed radii [m], ``0 <= r_g < r_b``, any shape (negative radii always raise).
        r_b: Radius of the admissible region [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).
        clip: If False (default), ``r_g >= r_b`` raises :class:`InputError`; if True such radii are clipped
            to the largest double below ``r_b``.

    Returns:
        Universal radii ``r_p`` [m], same shape.
    """
    rb = check_radius(r_b, "r_b")
    kk = check_k(k)
    rg = check_radii(r_g, "r_g")
    rg = clip_open_upper(rg, rb, "r_g", clip)
    return saturate_inverse(rg, rb, kk, "r_g")
