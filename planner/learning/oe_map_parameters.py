"""The parameters of the OE mappings (paper eqs. (6)-(7)) and their checks, shared by every map.

``k`` in the open interval (0, 1) (dimensionless), ``theta_b`` in (0, pi/2] [rad], ``r_b`` in (0, MAX_RADIUS] [m],
``delta`` in [0, MAX_RADIUS] [m]; ``k``, ``theta_b`` and ``r_b`` normal doubles, radii finite and >= 0. A value out
of its domain raises :class:`tooltransfer.errors.InputError` naming the argument. The maps themselves and the
reasons for these domains are in :mod:`tooltransfer.planner.learning.oe_mappings`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.validation import check_array

__all__ = ["MAX_RADIUS", "check_k", "check_radii", "check_radius", "check_theta_b", "first_bad"]

MAX_RADIUS: float = 1e300
"""Largest ``r_b`` and ``delta`` [m] accepted, so that sums like ``r_p + r_b + delta`` stay finite."""

TINY = float(np.finfo(np.float64).tiny)
"""The smallest normal double: ``k``, ``theta_b`` and ``r_b`` below it leave no room for the image."""


def first_bad(mask: NDArray[np.bool_], arr: NDArray[np.float64]) -> str:
    """The first value of ``arr`` where ``mask`` holds, and its flat index, for an error message."""
    i = int(np.argmax(mask.ravel()))
    return f"{arr.ravel()[i]!r} at flat index {i}"


def check_k(k: float) -> float:
    """``k`` as a float in (0, 1), a normal double."""
    try:
        v = float(k)
    except (TypeError, ValueError) as exc:
        raise InputError("k", "a real number in the open interval (0, 1)", repr(k)) from exc
    if not (TINY <= v < 1.0):
        raise InputError("k", "a real number in the open interval (0, 1) (a normal double, >= 2.2e-308)", repr(k))
    return v


def check_theta_b(theta_b: float) -> float:
    """``theta_b`` [rad] as a float in (0, pi/2], a normal double."""
    try:
        v = float(theta_b)
    except (TypeError, ValueError) as exc:
        raise InputError("theta_b", "a cone half-angle in (0, pi/2] rad", repr(theta_b)) from exc
    if not (TINY <= v <= np.pi / 2):
        raise InputError("theta_b", "a cone half-angle in (0, pi/2] rad (a normal double, >= 2.2e-308)", repr(theta_b))
    return v


def check_radius(value: float, field: str, *, allow_zero: bool = False) -> float:
    """A bound [m] as a float in (0, MAX_RADIUS] (normal), or in [0, MAX_RADIUS] with ``allow_zero``."""
    expected = f"a radius in [0, {MAX_RADIUS:g}] m" if allow_zero else f"a radius in [2.2e-308, {MAX_RADIUS:g}] m"
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(field, expected, repr(value)) from exc
    ok = (v >= 0.0 if allow_zero else v >= TINY) and v <= MAX_RADIUS
    if not ok:
        raise InputError(field, expected, repr(value))
    return v


def check_radii(value: ArrayLike, field: str) -> NDArray[np.float64]:
    """Finite radii >= 0 [m], any shape."""
    arr = check_array(value, field)
    if np.any(arr < 0.0):
        raise InputError(field, "radii >= 0 m", first_bad(arr < 0.0, arr))
    return arr
