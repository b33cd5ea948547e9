"""Initial paths for the switch NLP that go round the object instead of through it.

When the tool differs from the demonstration tool, the ``dmp`` path often passes through the object
(tens of millimetres deep for the T- and L-shapes): started there, IPOPT must first decide on which
side to take the tool out and spends most of its iterations (or all of them) doing so. A path round
the **configuration-space obstacle** is a much better start.

At a fixed heading ``psi`` the tool reference point ``x`` keeps the convex piece ``P`` (tool frame)
at least ``m`` away from a disc ``(c, R)`` iff ``x`` lies outside ``(c - R(psi) P)`` grown by
``R + m``; from a convex polygon ``O`` iff outside ``O - R(psi) P`` (the Minkowski difference, a
convex hull) grown by ``m``. The union over pieces and bodies is the C-obstacle (shapely). Its outer
boundary through the start and end of the switch gives two candidate paths, one each way round,
timed like the reference (arc length by the minimum-jerk profile, so knot k stays comparable with
the ``dmp`` knot k). The heading is the one of the ``dmp`` path's middle: along the path the true
heading differs by a few hundredths of a radian, so the candidate is nearly, not exactly, clear;
the NLP removes the rest. These are starting points only: the NLP, the exact shapely check and the
refinement are unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.planner.learning.virtual_motion import min_jerk
from tooltransfer.planner.planning.ss.verify import point_hulls, tool_geometry
from tooltransfer.tools.decompose import convex_decomposition
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.heading import rot


def c_obstacle(tool: Tool, psi: float, shapes: Sequence[Disc | shapely.Polygon], margin: float,
               quad_segs: int = 6) -> shapely.Geometry:
    """The C-obstacle (module docstring) of ``shapes`` for ``tool`` at heading ``psi`` [rad], grown
    by ``margin`` [m]: the tool reference points where some piece comes within ``margin`` of a shape."""
    verts, _ = tool_geometry(tool)
    placed = [v @ rot(psi).T for v in verts]
    parts = []
    for shape in shapes:
        if isinstance(shape, Disc):
            for p in placed:
                parts.append(shapely.buffer(shapely.Polygon(shape.centre - p), shape.radius + margin,
                                            quad_segs=quad_segs))
        else:
            for piece in convex_decomposition(shape):
                o = np.asarray(piece.exterior.coords, dtype=np.float64)[:-1]
                for p in placed:
                    pts = (o[:, None, :] - p[None, :, :]).reshape(-1, 2)
                    hull = point_hulls(pts)
                    parts.append(shapely.buffer(hull, margin, quad_segs=quad_segs) if margin > 0 else hull)
    return shapely.union_all(parts)


def round_paths(tool: Tool, start: NDArray[np.float64], end: NDArray[np.float64], psi: float,
                shapes: Sequence[Disc | shapely.Polygon], margin: float, n_knots: int,
                cobs: shapely.Geometry | None = None) -> list[NDArray[np.float64]]:
    """Candidate paths (N, 2) [m] from ``start`` to ``end`` (2,) along the outer boundary of the
    C-obstacle component nearest ``start``, one each way round (module docstring); empty when the
    boundary cannot be followed (both ends on the same point of it). ``cobs``: the C-obstacle if
    already built (:func:`c_obstacle` with the same arguments)."""
    if cobs is None:
        cobs = c_obstacle(tool, psi, shapes, margin)
    if cobs.is_empty:
        return []
    polys = list(cobs.geoms) if isinstance(cobs, shapely.MultiPolygon) else [cobs]
    a, b = shapely.Point(start), shapely.Point(end)
    comp = min(polys, key=lambda g: g.distance(a))
    ring = shapely.LineString(comp.exterior.coords)
    length = ring.length
    sa, sb = ring.project(a), ring.project(b)
    fwd = (sb - sa) % length
    u = min_jerk(np.linspace(0.0, 1.0, n_knots))
    out = []
    for span in (fwd, fwd - length):  # one way round, then the other
        if abs(span) < 1e-9:
            continue
        s = (sa + span * u) % length
        pts = shapely.get_coordinates(shapely.line_interpolate_point(ring, s))
        pts[0], pts[-1] = start, end
        out.append(pts)
    return out

