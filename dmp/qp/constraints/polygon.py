"""Positions inside a convex polygon (workspace, reach wedge, table)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint
from tooltransfer.errors import InputError
from tooltransfer.validation import check_array


class PositionPolygon(Constraint):
    """Keep the position inside the convex set ``{x : A x <= b}`` (n-D half-spaces).

    Rows are normalised to unit normals, so residuals are signed distances [m] to each side.

    Args:
        A: outward normals, shape (m, n); b: offsets (m,) [m].
    """

    def __init__(
        self, A: ArrayLike, b: ArrayLike, *, family: str = "workspace", window: tuple[float, float] | None = None
    ) -> None:
        super().__init__(family, window)
        a = check_array(A, "A", ndim=2)
        bb = check_array(b, "b", shape=(a.shape[0],))
        norms = np.linalg.norm(a, axis=1)
        if np.any(norms == 0.0):
            raise InputError("A", "rows with non-zero normals")
        self.A, self.b = a / norms[:, None], bb / norms

    @classmethod
    def from_vertices(
        cls, vertices: ArrayLike, *, family: str = "workspace", window: tuple[float, float] | None = None
    ) -> PositionPolygon:
        """Convex polygon from its vertices (V, 2) [m] in either orientation."""
        v = check_array(vertices, "vertices", shape=(None, 2))
        if v.shape[0] < 3:
            raise InputError("vertices", "at least 3 vertices", f"{v.shape[0]}")
        area2 = float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))
        if abs(area2) < 1e-15:
            raise InputError("vertices", "a polygon with positive area")
        if area2 < 0:
            v = v[::-1]
        edges = np.roll(v, -1, axis=0) - v
        cross = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
        if np.any(cross < -1e-12 * np.abs(cross).max()):
            raise InputError("vertices", "a convex polygon")
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)  # outward for CCW
        b = np.einsum("ij,ij->i", normals, v)
        return cls(normals, b, family=family, window=window)

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        kk = k.size
        return Coefficients(
            k, np.broadcast_to(self.A, (kk, *self.A.shape)), None, np.broadcast_to(self.b, (kk, self.b.size))
        )
