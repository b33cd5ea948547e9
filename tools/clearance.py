"""Clearance and penetration between a tool (at a pose, or swept between two) and a shape.

Definitions (all in metres, world frame):

* ``clearance``: the distance between the tool's outline and the shape, 0 when they touch or
  overlap.
* ``penetration_depth``: 0 when the interiors are disjoint. Against a disc of radius ``R`` centred
  at ``c`` it is ``R - sd(c, tool)``, with ``sd`` the signed distance from ``c`` to the tool outline
  (negative inside): how far the disc reaches past the tool's boundary. Against a polygon it is
  the largest separating-axis overlap over pairs of convex pieces (the minimum translation
  distance when both are convex, a lower bound of it otherwise).
* ``signed_distance``: clearance when apart, minus the penetration depth when overlapping.

A swept tool moves with position and yaw interpolated linearly between two poses. Its region is
covered by the convex hulls of each convex piece at consecutive sub-poses, grown by the bound
``rho * dyaw^2 / 8`` on the distance between a rotating point and its chord (``rho``: largest
distance of an outline vertex from the tool origin). Sub-steps are chosen so this bound is at
most ``tol``; swept clearances are therefore lower bounds, within ``tol`` of the exact value.
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.ops import unary_union

from tooltransfer.errors import InputError
from tooltransfer.tools.decompose import convex_decomposition
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, Obstacle
from tooltransfer.tools.pose import Pose2D
from tooltransfer.validation import check_positive


def tool_polygon(tool: Tool, pose: Pose2D) -> shapely.Polygon:
    """The tool's outline placed at ``pose`` (world) [m]."""
    return pose.place(tool.outline)


def tool_pieces(tool: Tool, pose: Pose2D) -> list[shapely.Polygon]:
    """The tool's convex pieces placed at ``pose`` (world) [m]."""
    return [pose.place(p) for p in tool.convex_pieces]


def _signed_distance_point(poly: shapely.Geometry, c: NDArray[np.float64]) -> float:
    pt = shapely.Point(c)
    d = float(poly.boundary.distance(pt))
    return -d if poly.contains(pt) else d


def _sat_overlap(a: shapely.Polygon, b: shapely.Polygon) -> float:
    """Minimum projection overlap of two convex polygons over their edge normals (<= 0: apart)."""
    pa = np.asarray(a.exterior.coords, dtype=np.float64)[:-1]
    pb = np.asarray(b.exterior.coords, dtype=np.float64)[:-1]
    best = np.inf
    for pts in (pa, pb):
        edges = np.roll(pts, -1, axis=0) - pts
        normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
        lens = np.hypot(normals[:, 0], normals[:, 1])
        normals = normals[lens > 0] / lens[lens > 0, None]
        ja, jb = pa @ normals.T, pb @ normals.T
        overlap = np.minimum(ja.max(0) - jb.min(0), jb.max(0) - ja.min(0))
        best = min(best, float(overlap.min()))
    return best


def _pieces_of(other: Obstacle) -> list[shapely.Polygon]:
    if isinstance(other, shapely.Polygon):
        return list(convex_decomposition(other))
    raise InputError("other", "a Disc or a shapely Polygon", type(other).__name__)


def _depth(pieces: list[shapely.Polygon], other: Obstacle) -> float:
    if isinstance(other, Disc):
        region = unary_union(pieces)
        return max(0.0, other.radius - _signed_distance_point(region, other.centre))
    depth = 0.0
    for a in pieces:
        for b in _pieces_of(other):
            depth = max(depth, _sat_overlap(a, b))
    return depth


def _clearance(pieces: list[shapely.Polygon], other: Obstacle) -> float:
    if isinstance(other, Disc):
        pt = shapely.Point(other.centre)
        return max(0.0, min(float(p.distance(pt)) for p in pieces) - other.radius)
    if not isinstance(other, shapely.Polygon):
        raise InputError("other", "a Disc or a shapely Polygon", type(other).__name__)
    return min(float(p.distance(other)) for p in pieces)


def clearance(tool: Tool, pose: Pose2D, other: Obstacle) -> float:
    """Distance [m] between the tool at ``pose`` and ``other``; 0 when touching or overlapping."""
    return _clearance(tool_pieces(tool, pose), other)


def penetration_depth(tool: Tool, pose: Pose2D, other: Obstacle) -> float:
    """Penetration depth [m] of the tool at ``pose`` and ``other`` (module docstring); >= 0."""
    return _depth(tool_pieces(tool, pose), other)


def signed_distance(tool: Tool, pose: Pose2D, other: Obstacle) -> float:
    """Clearance [m] when apart, minus the penetration depth when overlapping.

    Against a disc this is exactly ``sd(c, tool) - R``.
    """
    pieces = tool_pieces(tool, pose)
    if isinstance(other, Disc):
        return _signed_distance_point(unary_union(pieces), other.centre) - other.radius
    gap = _clearance(pieces, other)
    return gap if gap > 0.0 else -_depth(pieces, other)


def swept_pieces(
    tool: Tool, start: Pose2D, end: Pose2D, tol: float = 1e-5
) -> list[shapely.Polygon]:
    """Convex polygons (world) covering the tool swept from ``start`` to ``end``, within ``tol``."""
    tol = check_positive(tol, "tol")
    dyaw = abs(end.yaw - start.yaw)
    rho = tool.radius
    n = 1 if dyaw == 0.0 else max(1, int(np.ceil(dyaw / np.sqrt(8.0 * tol / rho))))
    grow = rho * (dyaw / n) ** 2 / 8.0
    poses = [start.interpolate(end, k / n) for k in range(n + 1)]
    out = []
    for a, b in pairwise(poses):
        for piece in tool.convex_pieces:
            hull = unary_union([a.place(piece), b.place(piece)]).convex_hull
            out.append(hull.buffer(grow, quad_segs=4) if grow > 0 else hull)
    return out


def swept_clearance(
    tool: Tool, start: Pose2D, end: Pose2D, other: Obstacle, tol: float = 1e-5
) -> float:
    """Lower bound [m], within ``tol``, on the smallest clearance along the straight motion."""
    return _clearance(swept_pieces(tool, start, end, tol), other)


def swept_penetration_depth(
    tool: Tool, start: Pose2D, end: Pose2D, other: Obstacle, tol: float = 1e-5
) -> float:
    """Penetration depth [m] of the swept region and ``other`` (module docstring); 0 if clear."""
    return _depth(swept_pieces(tool, start, end, tol), other)
