"""Boundary validation helpers: convert, check shape and values, name the field on failure."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError


def check_array(
    value: ArrayLike, field: str, *, ndim: int | None = None, shape: tuple[int | None, ...] | None = None
) -> NDArray[np.float64]:
    """Return ``value`` as a finite float64 array, or raise :class:`InputError` naming ``field``.

    ``shape`` may contain ``None`` for free axes.
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(field, "an array of real numbers", type(value).__name__) from exc
    if shape is not None:
        ndim = len(shape)
    if ndim is not None and arr.ndim != ndim:
        raise InputError(field, f"an array with {ndim} dimension(s)", f"shape {arr.shape}")
    if shape is not None:
        for axis, (want, have) in enumerate(zip(shape, arr.shape, strict=True)):
            if want is not None and want != have:
                raise InputError(field, f"size {want} along axis {axis}", f"shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(field, "finite values (no NaN or infinity)")
    return arr


def check_time(t: ArrayLike, field: str = "t", min_len: int = 3) -> NDArray[np.float64]:
    """Return a strictly increasing time vector of shape (T,) [s], T >= ``min_len``."""
    arr = check_array(t, field, ndim=1)
    if arr.size < min_len:
        raise InputError(field, f"at least {min_len} samples", f"{arr.size}")
    if np.any(np.diff(arr) <= 0.0):
        k = int(np.argmax(np.diff(arr) <= 0.0))
        raise InputError(field, "strictly increasing times", f"t[{k + 1}] <= t[{k}]")
    return arr


def check_positive(value: float, field: str) -> float:
    """Return ``value`` as a float if it is finite and > 0."""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise InputError(field, "a positive real number", repr(value)) from exc
    if not np.isfinite(v) or v <= 0.0:
        raise InputError(field, "a positive finite number", repr(value))
    return v
