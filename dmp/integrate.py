"""Fixed-step RK4 reference integrator of the DMP (for checking the exact rollout)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

ForcingFn = Callable[[float], NDArray[np.float64]]


def rk4_rollout(
    t: NDArray[np.float64],
    x0: NDArray[np.float64],
    g: NDArray[np.float64],
    v0: NDArray[np.float64],
    tau: float,
    alpha_z: float,
    beta_z: float,
    forcing: ForcingFn,
    max_step: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Integrate eqs. (1)-(2) with classical RK4, sub-stepping so no step exceeds ``max_step``.

    ``forcing(t_rel)`` returns ``f`` (n,) at time ``t_rel`` [s] from the start. Returns positions
    and velocities ``dx/dt``, each (T, n), at the times ``t`` (T,) [s].
    """

    def deriv(
        tr: float, y: NDArray[np.float64], v: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return v / tau, (alpha_z * (beta_z * (g - y) - v) + forcing(tr)) / tau

    x = np.empty((t.size, x0.size))
    v = np.empty_like(x)
    y, z = x0.astype(np.float64).copy(), tau * v0.astype(np.float64)
    x[0], v[0] = y, z / tau
    t_rel = t - t[0]
    for k in range(t.size - 1):
        n_sub = max(1, int(np.ceil((t_rel[k + 1] - t_rel[k]) / max_step - 1e-9)))
        h = (t_rel[k + 1] - t_rel[k]) / n_sub
        tr = t_rel[k]
        for _ in range(n_sub):
            k1y, k1z = deriv(tr, y, z)
            k2y, k2z = deriv(tr + h / 2, y + h / 2 * k1y, z + h / 2 * k1z)
            k3y, k3z = deriv(tr + h / 2, y + h / 2 * k2y, z + h / 2 * k2z)
            k4y, k4z = deriv(tr + h, y + h * k3y, z + h * k3z)
            y = y + h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y)
            z = z + h / 6 * (k1z + 2 * k2z + 2 * k3z + k4z)
            tr += h
        x[k + 1], v[k + 1] = y, z / tau
    return x, v
