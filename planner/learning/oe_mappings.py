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
near ``R``) and cancels in ``r_g + (R/k) W``; :func:`outer_radius_inverse` therefore polishes it with Newton
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
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.pose import wrap_angle as _wrap_unchecked
from tooltransfer.validation import check_array

__all__ = [
    "MAX_RADIUS",
    "angle_inverse",
    "angle_map",
    "inner_inverse_points",
    "inner_map_points",
    "inner_radius",
    "inner_radius_inverse",
    "outer_inverse_points",
    "outer_map_points",
    "outer_radius",
    "outer_radius_inverse",
    "outer_radius_printed",
    "outer_radius_printed_inverse",
    "wrap_angle",
]

MAX_RADIUS: float = 1e300
"""Largest ``r_b`` and ``delta`` [m] accepted, so that sums like ``r_p + r_b + delta`` stay finite."""

_TINY = float(np.finfo(np.float64).tiny)
_NEWTON_MAX = 60  # Newton steps polishing the Lambert-W inverse (2-3 suffice except near W's branch point)
_SERIES_U = 0.5  # below this, exp(-u) - 1 + u is summed as a series (no cancellation)


# --------------------------------------------------------------------------------------------------
# parameter validation


def _first_bad(mask: NDArray[np.bool_], arr: NDArray[np.float64]) -> str:
    i = int(np.argmax(mask.ravel()))
    return f"{arr.ravel()[i]!r} at flat index {i}"


def _check_k(k: float) -> float:
    try:
        v = float(k)
    except (TypeError, ValueError) as exc:
        raise InputError("k", "a real number in the open interval (0, 1)", repr(k)) from exc
    if not (_TINY <= v < 1.0):
        raise InputError("k", "a real number in the open interval (0, 1) (a normal double, >= 2.2e-308)", repr(k))
    return v


def _check_theta_b(theta_b: float) -> float:
    try:
        v = float(theta_b)
    except (TypeError, ValueError) as exc:
        raise InputError("theta_b", "a cone half-angle in (0, pi/2] rad", repr(theta_b)) from exc
    if not (_TINY <= v <= np.pi / 2):
        raise InputError("theta_b", "a cone half-angle in (0, pi/2] rad (a normal double, >= 2.2e-308)", repr(theta_b))
    return v


def _check_radius(value: float, field: str, *, allow_zero: bool = False) -> float:
    expected = f"a radius in [0, {MAX_RADIUS:g}] m" if allow_zero else f"a radius in [2.2e-308, {MAX_RADIUS:g}] m"
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(field, expected, repr(value)) from exc
    ok = (v >= 0.0 if allow_zero else v >= _TINY) and v <= MAX_RADIUS
    if not ok:
        raise InputError(field, expected, repr(value))
    return v


def _check_radii(value: ArrayLike, field: str) -> NDArray[np.float64]:
    """Finite radii >= 0 [m], any shape."""
    arr = check_array(value, field)
    if np.any(arr < 0.0):
        raise InputError(field, "radii >= 0 m", _first_bad(arr < 0.0, arr))
    return arr


# --------------------------------------------------------------------------------------------------
# the saturating core shared by (6) and inner (7): y = b (1 - exp(-k x / b)), x >= 0, y in [0, b)


def _ratio(k: float, x: NDArray[np.float64], b: float) -> NDArray[np.float64]:
    """``u = k x / b >= 0`` without spurious overflow (``x / b`` may overflow where ``k x / b`` does not)."""
    with np.errstate(over="ignore"):  # an infinite u is the right limit: the maps saturate
        q = x / b
        return np.where(np.isinf(q), (k * x) / b, k * q)  # k normal: k x is normal whenever x / b overflows


def _saturate(x: NDArray[np.float64], b: float, k: float) -> NDArray[np.float64]:
    """``b (1 - exp(-k x / b))`` for ``x >= 0``, strictly below ``b``; same shape as ``x``."""
    u = _ratio(k, x, b)
    y = -b * np.expm1(-u)
    # u subnormal or zero: b * u loses relative precision; exp(-u) - 1 = -u exactly there.
    y = np.where(u < _TINY, k * x, y)
    return np.minimum(y, np.nextafter(b, 0.0))


def _saturate_inverse(y: NDArray[np.float64], b: float, k: float, field: str) -> NDArray[np.float64]:
    """``-(b / k) ln(1 - y / b)`` for ``0 <= y < b``; same shape as ``y``."""
    t = y / b
    near = t > 0.5
    # ln(1 - t): log1p for t <= 1/2; for t > 1/2 the distance b - y is exact (Sterbenz), use log of it.
    lg_small = -np.log1p(-np.minimum(t, 0.5))
    lg_near = -np.log(np.where(near, (b - y) / b, 0.5))
    lg = np.where(near, lg_near, lg_small)
    with np.errstate(over="ignore"):
        x = (lg * b) / k
        x = np.where(t < _TINY, y / k, x)  # t subnormal or zero: ln(1 - t) = -t exactly, keep y's precision
    if not np.all(np.isfinite(x)):
        raise InputError(field, f"values whose preimage is representable for k = {k!r} (it overflows)")
    return x


def _clip_open_upper(y: NDArray[np.float64], b: float, field: str, clip: bool) -> NDArray[np.float64]:
    """Enforce ``y < b`` for an image open at ``b``: clip to the largest double below ``b`` or raise."""
    beyond = y >= b
    if np.any(beyond):
        if not clip:
            raise InputError(
                field, f"values strictly inside the image bound {b!r} (pass clip=True to clip)", _first_bad(beyond, y)
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
    tb = _check_theta_b(theta_b)
    kk = _check_k(k)
    tg = check_array(theta_g, "theta_g")
    return np.copysign(_saturate(np.abs(tg), tb, kk), tg)


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
    tb = _check_theta_b(theta_b)
    kk = _check_k(k)
    th = check_array(theta, "theta")
    a = _clip_open_upper(np.abs(th), tb, "theta", clip)
    return np.copysign(_saturate_inverse(a, tb, kk, "theta"), th)


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
    rb = _check_radius(r_b, "r_b")
    kk = _check_k(k)
    rp = _check_radii(r_p, "r_p")
    return _saturate(rp, rb, kk)


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
    rb = _check_radius(r_b, "r_b")
    kk = _check_k(k)
    rg = _check_radii(r_g, "r_g")
    rg = _clip_open_upper(rg, rb, "r_g", clip)
    return _saturate_inverse(rg, rb, kk, "r_g")


# --------------------------------------------------------------------------------------------------
# eq. (7), outer space: the monotone form of docs/design.md section 5, and the printed form


def _expm1_neg_plus(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """``exp(-u) - 1 + u`` for ``0 <= u <= 1/2`` by its alternating series (relative accuracy ~1 ulp)."""
    acc = np.ones_like(u)
    for n in range(22, 2, -1):  # sum_{n>=2} (-u)^n / n! = (u^2 / 2) (1 - u/3 (1 - u/4 (...))); 0.5^23/23! < 1e-29
        acc = 1.0 - acc * u / n
    return 0.5 * u * u * acc


def _outer_excess(rp: NDArray[np.float64], R: float, k: float) -> NDArray[np.float64]:
    """``r_g - R = r_p + R (exp(-k r_p / R) - 1)`` without cancellation; ``>= 0``, same shape."""
    u = _ratio(k, rp, R)
    # small u: r_p (1 - k) + R (exp(-u) - 1 + u), two non-negative terms
    us = np.minimum(u, _SERIES_U)
    small = rp * (1.0 - k) + R * _expm1_neg_plus(us)
    # large u: R (1 - exp(-u)) <= 0.79 k r_p, so the subtraction loses at most ~2 bits
    large = rp + R * np.expm1(-u)
    return np.where(u <= _SERIES_U, small, large)


def _outer_newton(rp: NDArray[np.float64], e: NDArray[np.float64], R: float, k: float) -> NDArray[np.float64]:
    """Polish ``r_p`` so that ``_outer_excess(r_p) = e``; Newton on a convex increasing function.

    ``F(r) = excess(r) - e`` has ``F' = 1 - k exp(-k r / R) >= 1 - k > 0`` and ``F'' > 0``: after the first
    step every iterate lies right of the root and decreases monotonically to it (quadratically once close).
    The closed form is only accurate to about ``sqrt(eps)`` near ``W_0``'s branch point (``k`` near 1,
    ``r_g`` near ``R``), so a few steps are needed there; elsewhere one step changes nothing.
    """
    for _ in range(_NEWTON_MAX):
        slope = 1.0 - k * np.exp(-_ratio(k, rp, R))
        new = np.maximum(rp - (_outer_excess(rp, R, k) - e) / slope, 0.0)
        done = np.all(np.abs(new - rp) <= 2.0 * np.finfo(np.float64).eps * new)
        rp = new
        if done:
            break
    return rp


def _outer_sum(R: float, excess: NDArray[np.float64], field: str) -> NDArray[np.float64]:
    with np.errstate(over="ignore"):
        rg = R + excess
    if not np.all(np.isfinite(rg)):
        raise InputError(field, "radii whose outer-space image is finite (below about 1e308 m)")
    return rg


def outer_radius(r_p: ArrayLike, r_b: float, k: float, *, delta: float = 0.0) -> NDArray[np.float64]:
    """Eq. (7), outer space, monotone form (docs/design.md section 5): ``r_g = r_p + R exp(-k r_p / R)``.

    ``R = r_b + delta``: the safety margin of section IV.E. Strictly increasing, ``r_g(0) = R``,
    ``r_g - r_p -> 0`` far away (tail effect).

    Args:
        r_p: Universal radii [m] about the obstacle centre, ``>= 0``, any shape (the image must be finite:
            below about 1e308 m).
        r_b: Obstacle radius [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).
        delta: Safety margin [m], in [0, MAX_RADIUS].

    Returns:
        Condensed radii ``r_g`` [m], same shape, with ``r_g >= r_b + delta`` always (so ``r_g > r_b`` for
        ``delta > 0``); ``r_g = R`` at ``r_p = 0`` and, by rounding, for ``r_p`` below about one ulp of ``R``.
    """
    R = _check_radius(r_b, "r_b") + _check_radius(delta, "delta", allow_zero=True)
    kk = _check_k(k)
    rp = _check_radii(r_p, "r_p")
    return _outer_sum(R, _outer_excess(rp, R, kk), "r_p")


def outer_radius_inverse(
    r_g: ArrayLike, r_b: float, k: float, *, delta: float = 0.0, clip: bool = False
) -> NDArray[np.float64]:
    """Exact inverse of the monotone outer (7): ``r_p = r_g + (R / k) W_0(-k exp(-k r_g / R))``.

    ``R = r_b + delta``; ``W_0`` is the principal branch of Lambert W (``scipy.special.lambertw``). The
    closed form is polished by Newton steps on the cancellation-free excess ``r_g - R`` (the sum
    ``r_g + (R/k) W`` cancels when ``r_g`` is close to ``R``, and ``W_0`` is ill-conditioned near its branch
    point when ``k`` is close to 1): the result is accurate to a few ulps of the exact preimage of ``r_g``.

    Args:
        r_g: Condensed radii [m], ``r_g >= R``, finite, any shape (negative radii always raise).
        r_b: Obstacle radius [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).
        delta: Safety margin [m], in [0, MAX_RADIUS].
        clip: If False (default), ``r_g < R`` (beyond the image bound, inside the margin) raises
            :class:`InputError`; if True such radii are clipped to ``R`` (image closed there) and give 0.

    Returns:
        Universal radii ``r_p`` [m], same shape, ``>= 0``.
    """
    R = _check_radius(r_b, "r_b") + _check_radius(delta, "delta", allow_zero=True)
    kk = _check_k(k)
    rg = _check_radii(r_g, "r_g")
    below = rg < R
    if np.any(below):
        if not clip:
            raise InputError("r_g", f"radii >= r_b + delta = {R!r} m (pass clip=True to clip)", _first_bad(below, rg))
        rg = np.where(below, R, rg)
    e = rg - R  # exact for r_g <= 2R (Sterbenz)
    v = _ratio(kk, rg, R)
    from scipy.special import lambertw  # imported here: scipy.special is slow to import, and only this needs it

    w = np.real(lambertw(-kk * np.exp(-v), 0))
    rp = np.maximum(rg + (R * w) / kk, 0.0)
    return np.where(e == 0.0, 0.0, _outer_newton(rp, e, R, kk))


def outer_radius_printed(r_p: ArrayLike, r_b: float, k: float) -> NDArray[np.float64]:
    """Eq. (7), outer space *as printed*: ``r_g = r_b + r_b exp(-k r_p / r_b)``. For comparison only.

    Strictly **decreasing** (order-reversing): ``r_p = 0`` maps to ``2 r_b`` and far points approach
    ``r_b`` from above. The project uses :func:`outer_radius` instead (docs/design.md section 9).

    Args:
        r_p: Universal radii [m], ``>= 0``, any shape.
        r_b: Obstacle radius [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).

    Returns:
        ``r_g`` [m], same shape, with ``r_b < r_g <= 2 r_b`` always (the smallest double above ``r_b`` is
        returned where ``exp`` underflows or rounding would land on ``r_b``).
    """
    rb = _check_radius(r_b, "r_b")
    kk = _check_k(k)
    rp = _check_radii(r_p, "r_p")
    u = _ratio(kk, rp, rb)
    return np.maximum(rb + rb * np.exp(-u), np.nextafter(rb, np.inf))


def outer_radius_printed_inverse(r_g: ArrayLike, r_b: float, k: float, *, clip: bool = False) -> NDArray[np.float64]:
    """Exact inverse of the printed outer (7): ``r_p = -(r_b / k) ln((r_g - r_b) / r_b)``.

    Args:
        r_g: Radii [m] in ``(r_b, 2 r_b]``, any shape (negative radii always raise).
        r_b: Obstacle radius [m], in (0, MAX_RADIUS].
        k: Adjusting factor in (0, 1).
        clip: If False (default), ``r_g <= r_b`` or ``r_g > 2 r_b`` raises :class:`InputError`; if True they
            are clipped to the smallest double above ``r_b`` and to ``2 r_b`` (giving 0) respectively.

    Returns:
        ``r_p`` [m], same shape, ``>= 0``.
    """
    rb = _check_radius(r_b, "r_b")
    kk = _check_k(k)
    rg = _check_radii(r_g, "r_g")
    lo, hi = rg <= rb, rg > 2.0 * rb
    if np.any(lo | hi):
        if not clip:
            raise InputError(
                "r_g",
                f"radii in (r_b, 2 r_b] = ({rb!r}, {2.0 * rb!r}] m (pass clip=True to clip)",
                _first_bad(lo | hi, rg),
            )
        rg = np.where(lo, np.nextafter(rb, np.inf), np.where(hi, 2.0 * rb, rg))
    s = (rg - rb) / rb  # r_g - r_b exact (Sterbenz), s in (0, 1]
    with np.errstate(over="ignore"):
        rp = (-np.log(s) * rb) / kk
    if not np.all(np.isfinite(rp)):
        raise InputError("r_g", f"radii whose preimage is representable for k = {kk!r} (it overflows)")
    return rp


# --------------------------------------------------------------------------------------------------
# point maps: move points radially about reference points


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
    rb = _check_radius(r_b, "r_b")
    kk = _check_k(k)
    c, r, u = _offsets(x_p, center, "x_p")
    return c + u * _saturate(r, rb, kk)[..., None]


def inner_inverse_points(
    x_g: ArrayLike, center: ArrayLike, r_b: float, k: float, *, clip: bool = False
) -> NDArray[np.float64]:
    """Exact inverse of :func:`inner_map_points`; ``clip`` as in :func:`inner_radius_inverse`.

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
    rb = _check_radius(r_b, "r_b")
    kk = _check_k(k)
    c, r, u = _offsets(x_g, center, "x_g")
    r = _clip_open_upper(r, rb, "x_g", clip)
    return c + u * _saturate_inverse(r, rb, kk, "x_g")[..., None]


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
    R = _check_radius(r_b, "r_b") + _check_radius(delta, "delta", allow_zero=True)
    kk = _check_k(k)
    c, r, u = _offsets(x_p, center, "x_p")
    if np.any(r == 0.0):
        raise InputError("x_p", "points distinct from the centre (its outer-space image direction is undefined)")
    return c + u * _outer_sum(R, _outer_excess(r, R, kk), "x_p")[..., None]


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
