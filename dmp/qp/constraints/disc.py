"""Stay outside a disc (obstacle, the Omni's inner reach radius), linearised sequentially."""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint
from tooltransfer.errors import InputError
from tooltransfer.validation import check_array, check_positive

Side = Literal["left", "right"]


def _norms(d: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row norms of ``d`` (K, n) (an einsum: faster than ``np.linalg.norm(d, axis=1)`` here)."""
    return np.sqrt(np.einsum("ij,ij->i", d, d))


def _left_of(travel: NDArray[np.float64]) -> NDArray[np.float64]:
    """The unit vector a quarter turn counter-clockwise from ``travel`` (2,) (from +x when it is zero)."""
    norm = np.linalg.norm(travel)
    u = travel / norm if norm > 0 else np.array([1.0, 0.0])
    return np.array([-u[1], u[0]])


class OutsideDisc(Constraint):
    """Keep the position outside the disc ``|x - c| >= r``, as one tangent half-plane per sample.

    At each sample the row is ``n . x >= n . c + r`` with ``n`` the unit vector from the centre to
    the linearisation point (the previous iterate, in the sequential convex loop). Satisfying the
    row implies the true constraint, so the linearisation is conservative; it also fixes the side
    of passage to that of the linearisation path. ``side`` lets the caller choose it: ``"left"``
    passes with the obstacle on the path's right (the path goes left of it, seen from start to
    goal), ``"right"`` the other way; samples whose linearisation point lies on the wrong side are
    reflected across the start-goal line through the centre. A point exactly at the centre is
    pushed towards the chosen side (to the left when no side is chosen).

    Args:
        center: (2,) [m]; radius: [m] (include any safety margin).
    """

    linearised = True

    def __init__(
        self,
        center: ArrayLike,
        radius: float,
        *,
        side: Side | None = None,
        family: str = "obstacle",
        window: tuple[float, float] | None = None,
    ) -> None:
        super().__init__(family, window)
        self.center = check_array(center, "center", shape=(2,))
        self.radius = check_positive(radius, "radius")
        if side not in (None, "left", "right"):
            raise InputError("side", "'left', 'right' or None", repr(side))
        self.side = side

    def normals(
        self, x_lin: NDArray[np.float64], travel: NDArray[np.float64], side: Side | None
    ) -> NDArray[np.float64]:
        """Unit normals (K, 2) from the centre towards the points ``x_lin`` (K, 2)."""
        d = x_lin - self.center
        left = None  # the unit normal to the left of ``travel``: only where a side or a point at the centre needs it
        if side is not None:
            left = _left_of(travel)
            sgn = 1.0 if side == "left" else -1.0
            off = d @ left
            inside = _norms(d) < self.radius
            wrong = inside & (sgn * off < 0)
            d[wrong] -= 2.0 * off[wrong, None] * left
        r = _norms(d)
        tiny = r < 1e-12 * max(1.0, self.radius)
        if tiny.any():
            d[tiny] = (-1.0 if side == "right" else 1.0) * (_left_of(travel) if left is None else left)
            r[tiny] = 1.0
        return d / r[:, None]

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        if x_lin.shape[1] != 2:
            raise InputError("OutsideDisc", "a planar (2-D) motion", f"{x_lin.shape[1]}-D")
        n = self.normals(x_lin[k], x_lin[-1] - x_lin[0], self.side)
        bound = -(n @ self.center + self.radius)
        return Coefficients(k, -n[:, None, :], None, bound[:, None])

    def violation(self, t: NDArray[np.float64], x: NDArray[np.float64], v: NDArray[np.float64]) -> float:
        """True violation ``max(r - |x - c|, 0)`` [m] (whatever the chosen side)."""
        k = self.samples(t)
        if k.size == 0:
            return 0.0
        return float(max(0.0, (self.radius - _norms(x[k] - self.center)).max()))
