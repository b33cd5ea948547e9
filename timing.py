"""Time parametrization of a plan's pieces under a maximum tool speed and acceleration.

* Straight or given geometric paths (approach, retreat, switches) follow a minimum-jerk profile of
  arc length, ``s(u) = L (10 u^3 - 15 u^4 + 6 u^5)``, whose peak speed is ``1.875 L / T`` and
  peak acceleration ``(10 / sqrt 3) L / T^2``: :func:`min_jerk_duration` gives the shortest ``T``.
* The pushes keep the timing of the condensed DMP motion, stretched by one factor for the whole
  OE motion (the shape and the stops at switch instants are kept): :func:`stretch_factor`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tooltransfer.validation import check_array, check_positive

PEAK_SPEED = 1.875
PEAK_ACCEL = 10.0 / np.sqrt(3.0)


def min_jerk_duration(length: float, v_max: float, a_max: float) -> float:
    """Shortest duration [s] of a minimum-jerk move of ``length`` [m] within ``v_max`` [m/s] and
    ``a_max`` [m/s^2] (0 for a zero-length move)."""
    v_max, a_max = check_positive(v_max, "v_max"), check_positive(a_max, "a_max")
    if length <= 0:
        return 0.0
    return float(max(PEAK_SPEED * length / v_max, np.sqrt(PEAK_ACCEL * length / a_max)))


def min_jerk_along(
    path: NDArray[np.float64], duration: float, n: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sample a polyline ``path`` (K, d) at ``n`` times over ``duration`` [s] with a minimum-jerk
    arc-length profile; returns times (n,) [s] and points (n, d)."""
    p = check_array(path, "path", ndim=2)
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    u = np.linspace(0.0, 1.0, n)
    prof = u**3 * (10.0 - 15.0 * u + 6.0 * u**2) * s[-1]
    if s[-1] <= 0:
        return u * duration, np.repeat(p[:1], n, axis=0)
    pts = np.column_stack([np.interp(prof, s, p[:, j]) for j in range(p.shape[1])])
    return u * duration, pts


def stretch_factor(t: NDArray[np.float64], xy: NDArray[np.float64], v_max: float, a_max: float) -> float:
    """Smallest factor ``c >= 1`` such that the path ``xy`` (T, 2) [m] timed by ``c t`` (T,) [s]
    stays within ``v_max`` and ``a_max`` (speeds scale as 1/c, accelerations as 1/c^2)."""
    v_max, a_max = check_positive(v_max, "v_max"), check_positive(a_max, "a_max")
    if t.size < 3:
        return 1.0
    v = np.gradient(xy, t, axis=0)
    a = np.gradient(v, t, axis=0)
    speed = float(np.linalg.norm(v, axis=1).max())
    acc = float(np.linalg.norm(a, axis=1).max())
    return float(max(1.0, speed / v_max, np.sqrt(acc / a_max)))
