"""Stay a clearance away from a convex polygon (an obstacle), linearised sequentially."""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint
from tooltransfer.errors import InputError
from tooltransfer.validation import check_array


class OutsidePolygon(Constraint):
    """Keep the position at least ``clearance`` [m] from the convex polygon ``vertices`` (V, 2) [m].

    At each sample the row is ``n . x >= n . p + clearance`` with ``p`` the polygon's point nearest
    the linearisation point and ``n`` the unit direction from ``p`` to it (for a point inside, the
    edge it is least deep behind). The polygon lies behind that supporting line, so the row
    implies the true constraint (conservative, like a disc's tangent), and it fixes the side of
    passage to that of the linearisation path.
    """

    linearised = True

    def __init__(
        self, vertices: ArrayLike, clearance: float = 0.0, *, family: str = "obstacle",
        window: tuple[float, float] | None = None,
    ) -> None:
        super().__init__(family, window)
        v = check_array(vertices, "vertices", shape=(None, 2))
        poly = shapely.Polygon(v)
        if v.shape[0] < 3 or not poly.is_valid or poly.area <= 0:
            raise InputError("vertices", "a valid polygon with positive area", f"{v.shape[0]} vertices")
        if abs(poly.convex_hull.area - poly.area) > 1e-12 * poly.area:
            raise InputError("vertices", "a convex polygon", "a non-convex outline")
        if not np.isfinite(clearance) or clearance < 0:
            raise InputError("clearance", "a finite number >= 0 [m]", repr(clearance))
        ring = np.asarray(shapely.geometry.polygon.orient(poly, 1.0).exterior.coords)[:-1]
        edges = np.roll(ring, -1, axis=0) - ring
        n = np.stack([edges[:, 1], -edges[:, 0]], axis=1)  # outward for counter-clockwise
        n /= np.linalg.norm(n, axis=1)[:, None]
        self.polygon, self.normals, self.offsets = poly, n, np.einsum("ij,ij->i", n, ring)
        self.clearance = float(clearance)

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        if x_lin.shape[1] != 2:
            raise InputError("OutsidePolygon", "a planar (2-D) motion", f"{x_lin.shape[1]}-D")
        p = x_lin[k]
        side = p @ self.normals.T - self.offsets  # (K, E) signed distance beyond each edge line
        e = np.argmax(side, axis=1)
        n, b = self.normals[e].copy(), self.offsets[e].copy()
        out = side[np.arange(k.size), e] > 1e-12
        if np.any(out):  # outside: the supporting line at the nearest point (smooth round corners)
            near = shapely.get_coordinates(shapely.shortest_line(self.polygon, shapely.points(p[out])))[::2]
            d = p[out] - near
            n[out] = d / np.linalg.norm(d, axis=1)[:, None]
            b[out] = np.einsum("ij,ij->i", n[out], near)
        return Coefficients(k, -n[:, None, :], None, -(b + self.clearance)[:, None])

    def violation(self, t: NDArray[np.float64], x: NDArray[np.float64], v: NDArray[np.float64]) -> float:
        """True violation ``max(clearance - distance to the polygon, 0)`` [m]."""
        k = self.samples(t)
        if k.size == 0:
            return 0.0
        d = shapely.distance(self.polygon, shapely.points(x[k]))
        return float(max(0.0, (self.clearance - d).max()))
