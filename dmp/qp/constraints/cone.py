"""Velocity inside a tool's push cone (paper Fig. 5: the yellow ranges)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint
from tooltransfer.errors import InputError


def cone_rows(direction: float | NDArray[np.float64], theta_b: float | NDArray[np.float64]) -> NDArray[np.float64]:
    """Rows ``A`` of ``A v <= 0`` keeping a planar velocity in the cone of half-angle ``theta_b`` [rad]
    about ``direction`` [rad]: the negated inward unit normals of the edges at ``direction +- theta_b``.

    Shape (2, 2) for one direction, (K, 2, 2) for directions of shape (K,) (one cone per sample; ``theta_b``
    one for all or (K,)).
    """
    hi, lo = direction + theta_b, direction - theta_b
    s_hi, c_hi, s_lo, c_lo = np.sin(hi), np.cos(hi), np.sin(lo), np.cos(lo)
    rows = np.empty((*np.shape(hi), 2, 2), dtype=np.result_type(s_hi, s_lo))
    # -n . v <= 0 with the inward normals n of the two edges, (sin hi, -cos hi) and (-sin lo, cos lo)
    rows[..., 0, 0], rows[..., 0, 1] = -s_hi, c_hi
    rows[..., 1, 0], rows[..., 1, 1] = s_lo, -c_lo
    return rows


class VelocityCone(Constraint):
    """Planar velocity in the cone of half-angle ``theta_b`` around the push direction ``phi``.

    ``{v : n1 . v >= 0, n2 . v >= 0}`` with ``n1``, ``n2`` the inward unit normals of the cone's
    edges at ``phi +- theta_b``. Residuals are in m/s. Zero velocity is inside.

    Args:
        direction: push direction ``phi`` [rad] from +x, counter-clockwise.
        theta_b: half-angle [rad], in (0, pi/2).
        window: time interval [s] of the push.
    """

    def __init__(
        self, direction: float, theta_b: float, *, family: str = "cone", window: tuple[float, float] | None = None
    ) -> None:
        super().__init__(family, window)
        if not np.isfinite(direction):
            raise InputError("direction", "a finite angle [rad]", repr(direction))
        if not (0.0 < theta_b < np.pi / 2):
            raise InputError("theta_b", "a half-angle in (0, pi/2) rad", repr(theta_b))
        self.direction, self.theta_b = float(direction), float(theta_b)
        self.rows_vel = cone_rows(direction, theta_b)

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        if x_lin.shape[1] != 2:
            raise InputError("VelocityCone", "a planar (2-D) motion", f"{x_lin.shape[1]}-D")
        return Coefficients(k, None, np.broadcast_to(self.rows_vel, (k.size, 2, 2)), np.zeros((k.size, 2)))
