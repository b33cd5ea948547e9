"""Where a tool outline touches a disc: the nearest point of the outline to the disc's centre.

A straight face touching a disc touches it at the foot of the perpendicular from the centre (the
contact normal is the face's outward normal); a vertex touching it is a point contact whose normal
joins the vertex and the centre. Both are the nearest point of the outline's boundary to the
centre, so one routine serves faces and corners: :class:`Outline` holds the edges of a tool outline
in the tool frame and finds, for a batch of centres, the nearest boundary point, its distance, the
edge it lies on and whether it is an edge's interior or one of its ends (a vertex).

A curved outline (the finger's 6 mm head of Table II) is represented by its polygon in the tool
file; there the contact passes from facet to vertex to facet, and at a vertex the normal joins it
to the centre, the same normal a round head would give at that point. Pushes are planned only
on the straight segments named as faces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.tools.model import Tool

#: Fraction of an edge's length within which a nearest point counts as the edge's end (a vertex).
VERTEX_TOL = 1e-9


@dataclass(frozen=True)
class Nearest:
    """Nearest boundary points of an outline to a batch of centres (tool frame).

    Attributes:
        point: (B, 2) nearest boundary point [m].
        distance: (B,) distance [m] from the centre to it (negative when the centre is inside).
        normal: (B, 2) unit normal from the point to the centre (the edge's outward normal for an
            interior point of an edge, or when the centre is inside).
        edge: (B,) index of the edge (``start[edge]`` to ``start[edge + 1]``).
        along: (B,) fraction along that edge, in [0, 1].
        vertex: (B,) whether the point is an end of its edge.
    """

    point: NDArray[np.float64]
    distance: NDArray[np.float64]
    normal: NDArray[np.float64]
    edge: NDArray[np.intp]
    along: NDArray[np.float64]
    vertex: NDArray[np.bool_]


@dataclass(frozen=True)
class Outline:
    """Edges of a closed counter-clockwise outline in the tool frame.

    Attributes:
        start: (M, 2) first vertex of each edge [m]; edge ``m`` runs to ``start[(m + 1) % M]``.
        direction: (M, 2) edge vectors [m]; length2: (M,) squared lengths [m^2].
        normal: (M, 2) outward unit normals.
        radius: largest distance [m] of a vertex from the tool frame's origin (a bounding circle).
    """

    start: NDArray[np.float64]
    direction: NDArray[np.float64]
    length2: NDArray[np.float64]
    normal: NDArray[np.float64]
    radius: float

    @classmethod
    def of(cls, tool: Tool) -> Outline:
        """The outline of ``tool`` (counter-clockwise after :class:`Tool` validation)."""
        ring = np.asarray(tool.outline.exterior.coords, dtype=np.float64)[:-1]
        d = np.roll(ring, -1, axis=0) - ring
        keep = np.einsum("ij,ij->i", d, d) > 0
        ring, d = ring[keep], d[keep]
        l2 = np.einsum("ij,ij->i", d, d)
        n = np.stack([d[:, 1], -d[:, 0]], axis=1) / np.sqrt(l2)[:, None]
        return cls(ring, d, l2, n, float(np.max(np.hypot(ring[:, 0], ring[:, 1]))))

    def nearest(self, p: NDArray[np.float64]) -> Nearest:
        """Nearest boundary points to centres ``p`` (B, 2) given in the tool frame [m]."""
        rel = p[:, None, :] - self.start[None]  # (B, M, 2)
        u = np.clip(np.einsum("bmi,mi->bm", rel, self.direction) / self.length2, 0.0, 1.0)
        foot = self.start[None] + u[..., None] * self.direction[None]
        diff = p[:, None, :] - foot
        d2 = np.einsum("bmi,bmi->bm", diff, diff)
        m = np.argmin(d2, axis=1)
        rows = np.arange(p.shape[0])
        q, dist, uu = foot[rows, m], np.sqrt(d2[rows, m]), u[rows, m]
        inside = self.contains(p)
        with np.errstate(invalid="ignore", divide="ignore"):
            n = np.where((dist > 1e-15)[:, None], (p - q) / dist[:, None], self.normal[m])
        n = np.where(inside[:, None], self.normal[m], n)
        vertex = (uu <= VERTEX_TOL) | (uu >= 1.0 - VERTEX_TOL)
        return Nearest(q, np.where(inside, -dist, dist), n, m, uu, vertex)

    def contains(self, p: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Whether the points ``p`` (B, 2) [m] lie strictly inside the outline (crossing number)."""
        a = self.start[None]
        b = np.roll(self.start, -1, axis=0)[None]
        py = p[:, None, 1]
        px = p[:, None, 0]
        crosses = (a[..., 1] > py) != (b[..., 1] > py)
        with np.errstate(invalid="ignore", divide="ignore"):
            xc = a[..., 0] + (py - a[..., 1]) * (b[..., 0] - a[..., 0]) / (b[..., 1] - a[..., 1])
        return (np.sum(crosses & (px < xc), axis=1) % 2) == 1
