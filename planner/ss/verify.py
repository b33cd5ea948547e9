"""Exact check of a switch path with shapely: the swept tool outline against the object and obstacles.

Between consecutive samples the tool moves with position and yaw interpolated linearly (as
:mod:`tools.clearance`). The region a convex piece sweeps over one step is covered by the convex
hull of the piece at the step's two poses, grown by ``rho * dyaw^2 / 8`` (``rho``: the farthest
outline vertex from the tool origin) for the rotation; that growth is subtracted from the hull's
distance, so the clearances here are lower bounds within that bound (below 1 um for the headings of
a switch). The hulls of all steps and pieces are built and measured in one vectorized shapely call.
Steps whose hull reaches into a shape get their penetration depth from
:func:`tools.clearance.swept_penetration_depth` (the union of the pieces, exact for a disc).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from planner.ss.heading import rot
from tools.clearance import swept_penetration_depth
from tools.model import Tool
from tools.objects import Disc, Obstacle
from tools.pose import Pose2D


@dataclass(frozen=True)
class SweepCheck:
    """Per-step clearances of a path against one shape.

    Attributes:
        gap: shape (K-1,), lower bound on the distance [m] between the swept tool over each step
            and the shape (negative: the hull overlaps it; see ``depth``).
        depth: shape (K-1,), penetration depth [m] of each step's swept tool (0 where apart).
    """

    gap: NDArray[np.float64]
    depth: NDArray[np.float64]

    @property
    def max_penetration(self) -> float:
        """Largest penetration depth [m] over the path."""
        return float(self.depth.max(initial=0.0))

    def min_clearance(self, steps: NDArray[np.bool_] | None = None) -> float:
        """Smallest clearance [m] (0 when touching or overlapping) over ``steps`` (default all)."""
        g = self.gap if steps is None else self.gap[steps]
        return float(max(0.0, g.min())) if g.size else float("inf")


def step_hulls(tool: Tool, xy: NDArray[np.float64], yaw: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """Convex hulls (K-1, P) of each convex piece over each step, and the rotation growth (K-1,) [m]."""
    r = rot(yaw)  # (K, 2, 2)
    pieces = []
    for piece in tool.convex_pieces:
        v = np.asarray(piece.exterior.coords, dtype=np.float64)[:-1]  # (V, 2)
        w = np.einsum("kij,vj->kvi", r, v) + xy[:, None, :]  # (K, V, 2)
        pts = np.concatenate([w[:-1], w[1:]], axis=1)  # (K-1, 2V, 2)
        pieces.append(shapely.convex_hull(shapely.multipoints(pts)))
    grow = tool.radius * np.diff(yaw) ** 2 / 8.0
    return np.stack(pieces, axis=1), grow


def sweep_check(tool: Tool, xy: NDArray[np.float64], yaw: NDArray[np.float64], shape: Disc | shapely.Polygon,
                hulls: tuple[NDArray, NDArray] | None = None, depth_tol: float = 1e-6) -> SweepCheck:
    """Clearance and penetration of the tool swept along ``xy`` (K, 2) [m] / ``yaw`` (K,) [rad]
    against ``shape`` (a :class:`~tools.objects.Disc` or a shapely polygon). ``hulls`` from
    :func:`step_hulls` may be passed to share them between shapes. Steps reaching into a disc by
    more than ``depth_tol`` [m], or intersecting a polygon, get their exact depth (and ``gap = -depth``);
    elsewhere the depth is ``max(0, -gap)``."""
    h, grow = hulls if hulls is not None else step_hulls(tool, xy, yaw)
    if isinstance(shape, Disc):
        d = shapely.distance(h, shapely.Point(shape.centre)).min(axis=1) - shape.radius - grow
        inside = d < -depth_tol
    else:
        d = shapely.distance(h, shape).min(axis=1) - grow
        inside = shapely.intersects(h, shape).any(axis=1)
    depth = np.maximum(0.0, -d)
    for k in np.flatnonzero(inside):
        depth[k] = swept_penetration_depth(tool, Pose2D(*xy[k], yaw[k]), Pose2D(*xy[k + 1], yaw[k + 1]), shape)
        d[k] = min(d[k], -depth[k])
    return SweepCheck(d, depth)


def sweep_checks(tool: Tool, xy: NDArray[np.float64], yaw: NDArray[np.float64], shape: Disc | shapely.Polygon,
                 obstacles: Sequence[Obstacle] = ()) -> tuple[SweepCheck, tuple[SweepCheck, ...]]:
    """:func:`sweep_check` against the object ``shape`` and each obstacle, sharing the hulls."""
    hulls = step_hulls(tool, xy, yaw)
    return sweep_check(tool, xy, yaw, shape, hulls), tuple(sweep_check(tool, xy, yaw, o, hulls) for o in obstacles)
