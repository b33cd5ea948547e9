"""Forcing-term scaling: how a learned shape generalises to a new start ``x0`` and goal ``g``.

Every mode is a matrix ``M(x0, g)`` of shape (n, n) applied to the learned forcing term,
``f(s) = M @ W.T @ psi(s)``; the weights ``W`` live in the mode's normalised frame.

- ``"none"`` (as printed in the paper): ``M = I``; the shape is reused as is.
- ``"amplitude"`` (Ijspeert et al. 2013): ``M = diag(g - x0)``; degenerate for a dimension that
  barely moves between start and goal.
- ``"similarity"``: ``M = |d| R`` with ``d = g - x0`` and ``R`` the smallest rotation taking the
  first axis onto ``d / |d|``; rotates and uniformly scales the demonstrated shape onto the new
  start-to-goal vector. Frame independent; the sensible default for planar paths.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError

ScalingMode = Literal["none", "amplitude", "similarity"]
SCALING_MODES: tuple[str, ...] = ("none", "amplitude", "similarity")


def rotation_onto(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Smallest rotation (n, n) that takes the unit vector ``e_1`` onto the unit vector ``v``."""
    n = v.size
    u = np.zeros(n)
    u[0] = 1.0
    c = float(u @ v)
    if c > 1.0 - 1e-15:
        return np.eye(n)
    if c < -1.0 + 1e-15:
        r = np.eye(n)
        r[0, 0] = -1.0
        if n > 1:
            r[1, 1] = -1.0
        return r
    k = np.outer(v, u) - np.outer(u, v)
    return np.eye(n) + k + (k @ k) / (1.0 + c)


def scaling_matrix(
    mode: str, x0: NDArray[np.float64], g: NDArray[np.float64], *, extent: float | None = None
) -> NDArray[np.float64]:
    """Return ``M(x0, g)`` (n, n) for a scaling ``mode``.

    Args:
        mode: one of :data:`SCALING_MODES`.
        x0, g: start and goal, shape (n,) [m].
        extent: when given (the size of the demonstrated motion [m]), a start-to-goal distance
            below 1e-6 of it is rejected as degenerate: used when fitting, where ``M`` is inverted.
    """
    if mode not in SCALING_MODES:
        raise InputError("scaling", f"one of {', '.join(SCALING_MODES)}", repr(mode))
    n = x0.size
    d = g - x0
    if mode == "none":
        return np.eye(n)
    tol = 1e-6 * extent if extent is not None else 0.0
    if mode == "amplitude":
        if extent is not None and np.any(np.abs(d) <= tol):
            dims = [int(i) for i in np.flatnonzero(np.abs(d) <= tol)]
            raise InputError(
                "scaling",
                "a start and goal that differ in every dimension for 'amplitude' scaling "
                f"(dimension(s) {dims} barely move); use 'similarity' or 'none'",
            )
        return np.diag(d)
    norm = float(np.linalg.norm(d))
    if extent is not None and norm <= tol:
        raise InputError(
            "scaling",
            "distinct start and goal for 'similarity' scaling (they coincide); use 'none'",
        )
    if norm == 0.0:
        return np.zeros((n, n))
    return norm * rotation_onto(d / norm)
