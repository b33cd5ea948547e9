"""Paper eq. (7), outer space: keep points outside a disc of radius ``R = r_b + delta`` about an obstacle.

The monotone form ``r_g = r_p + R exp(-k r_p / R)`` (docs/design.md section 5) with its Lambert-W inverse
polished by Newton steps, and the form as printed in the paper (order-reversing, for comparison only). The
derivation, the accuracy and the clipping rules are in :mod:`tooltransfer.planner.learning.oe_mappings`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.oe_map_parameters import check_k, check_radii, check_radius, first_bad
from tooltransfer.planner.learning.oe_mappings import ratio

__all__ = ["outer_radius", "outer_radius_inverse", "outer_radius_printed", "outer_radius_printed_inverse"]

_NEWTON_MAX = 60  # Newton steps polishing the Lambert-W inverse (2-3 suffice except near W's branch point)
_SERIES_U = 0.5  # below this, exp(-u) - 1 + u is summed as a series (no cancellation)


def _expm1_neg_plus(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """``exp(-u) - 1 + u`` for ``0 <= u <= 1/2`` by its alternating series (relative accuracy ~1 ulp)."""
    acc = np.ones_like(u)
    for n in range(22, 2, -1):  # sum_{n>=2} (-u)^n / n! = (u^2 / 2) (1 - u/3 (1 - u/4 (...))); 0.5^23/23! < 1e-29
        acc = 1.0 - acc * u / n
    return 0.5 * u * u * acc


def outer_excess(rp: NDArray[np.float64], R: float, k: float) -> NDArray[np.float64]:
    """``r_g - R = r_p + R (exp(-k r_p / R) - 1)`` without cancellation; ``>= 0``, same shape."""
    u = ratio(k, rp, R)
    # small u: r_p (1 - k) + R (exp(-u) - 1 + u), two non-negative terms
    us = np.minimum(u, _SERIES_U)
    small = rp * (1.0 - k) + R * _expm1_neg_plus(us)
    # large u: R (1 - exp(-u)) <= 0.79 k r_p, so the subtraction loses at most ~2 bits
    large = rp + R * np.expm1(-u)
    return np.where(u <= _SERIES_U, small, large)


def _outer_newton(rp: NDArray[np.float64], e: NDArray[np.float64], R: float, k: float) -> NDArray[np.float64]:
    """Polish ``r_p`` so that ``outer_excess(r_p) = e``; Newton on a convex increasing function.

    ``F(r) = excess(r) - e`` has ``F' = 1 - k exp(-k r / R) >= 1 - k > 0`` and ``F'' > 0``: after the first
    step every iterate lies right of the root and decreases monotonically to it (quadratically once close).
    The closed form is only accurate to about ``sqrt(eps)`` near ``W_0``'s branch point (``k`` near 1,
    ``r_g`` near ``R``), so a few steps are needed there; elsewhere one step changes nothing.
    """
    for _ in range(_NEWTON_MAX):
        slope = 1.0 - k * np.exp(-ratio(k, rp, R))
        new = np.maximum(rp - (outer_excess(rp, R, k) - e) / slope, 0.0)
        done = np.all(np.abs(new - rp) <= 2.0 * np.finfo(np.float64).eps * new)
        rp = new
        if done:
            break
    return rp


def outer_sum(R: float, excess: NDArray[np.float64], field: str) -> NDArray[np.float64]:
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
    R = check_radius(r_b, "r_b") + check_radius(delta, "delta", allow_zero=True)
    kk = check_k(k)
    rp = check_radii(r_p, "r_p")
    return outer_sum(R, outer_excess(rp, R, kk), "r_p")


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
    R = check_radius(r_b, "r_b") + check_radius(delta, "delta", allow_zero=True)
    kk = check_k(k)
    rg = check_radii(r_g, "r_g")
    below = rg < R
    if np.any(below):
        if not clip:
            raise InputError("r_g", f"radii >= r_b + delta = {R!r} m (pass clip=True to clip)", first_bad(below, rg))
        rg = np.where(below, R, rg)
    e = rg - R  # exact for r_g <= 2R (Sterbenz)
    v = ratio(kk, rg, R)
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
    rb = check_radius(r_b, "r_b")
    kk = check_k(k)
    rp = check_radii(r_p, "r_p")
    u = ratio(kk, rp, rb)
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
    rb = check_radius(r_b, "r_b")
    kk = check_k(k)
    rg = check_radii(r_g, "r_g")
    lo, hi = rg <= rb, rg > 2.0 * rb
    if np.any(lo | hi):
        if not clip:
            raise InputError(
                "r_g",
                f"radii in (r_b, 2 r_b] = ({rb!r}, {2.0 * rb!r}] m (pass clip=True to clip)",
                first_bad(lo | hi, rg),
            )
        rg = np.where(lo, np.nextafter(rb, np.inf), np.where(hi, 2.0 * rb, rg))
    s = (rg - rb) / rb  # r_g - r_b exact (Sterbenz), s in (0, 1]
    with np.errstate(over="ignore"):
        rp = (-np.log(s) * rb) / kk
    if not np.all(np.isfinite(rp)):
        raise InputError("r_g", f"radii whose preimage is representable for k = {kk!r} (it overflows)")
    return rp
