"""Exact check of a switch path with shapely: the swept tool outline against the object and obstacles.

Between consecutive samples the tool moves with position and yaw interpolated linearly (as
:mod:`tooltransfer.tools.clearance`). The region a convex piece sweeps over one step is covered by the convex
hull of the piece at the step's two poses, grown by ``rho * dyaw^2 / 8`` (``rho``: the farthest
outline vertex from the tool origin) for the rotation; that growth is subtracted from the hull's
distance, so the clearances here are lower bounds within that bound (below 1 um for the headings of
a switch). The hulls of all steps and pieces are built and measured in one vectorized shapely call.
Steps whose hull reaches into a shape get their penetration depth by the construction of
:func:`tooltransfer.tools.clearance.swept_penetration_depth` (sub-steps, grown hulls, their union; exact for a
disc): for a disc vectorized over all such steps (:func:`disc_depths`, the same numbers), for a
polygon step by step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.tools.clearance import swept_penetration_depth
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, Obstacle
from tooltransfer.tools.omni.heading import rot
from tooltransfer.tools.pose import Pose2D

_PIECES: dict[int, tuple[shapely.Polygon, tuple[NDArray[np.float64], ...], float]] = {}


def tool_geometry(tool: Tool) -> tuple[tuple[NDArray[np.float64], ...], float]:
    """The vertices (V, 2) [m] of each convex piece of ``tool`` (tool frame) and its radius ``rho``
    [m], cached per outline object (``Tool.convex_pieces`` decomposes and checks the outline on every
    access; the cache keeps the outline alive, so its id is not reused)."""
    hit = _PIECES.get(id(tool.outline))
    if hit is None or hit[0] is not tool.outline:
        verts = tuple(np.asarray(p.exterior.coords, dtype=np.float64)[:-1] for p in tool.convex_pieces)
        hit = _PIECES[id(tool.outline)] = (tool.outline, verts, tool.radius)
    return hit[1], hit[2]


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


def point_hulls(pts: NDArray[np.float64]) -> NDArray:
    """Convex hulls of point sets ``pts`` (..., P, 2) [m], one per leading index. Built from line
    strings through the points (GEOS hulls the coordinates whatever the geometry): faster than
    from multipoints, which shapely creates point by point."""
    return shapely.convex_hull(shapely.linestrings(pts))


def step_hulls(tool: Tool, xy: NDArray[np.float64], yaw: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """Convex hulls (K-1, P) of each convex piece over each step, and the rotation growth (K-1,) [m]."""
    r = rot(yaw)  # (K, 2, 2)
    pieces = []
    verts, rho = tool_geometry(tool)
    for v in verts:
        w = np.einsum("kij,vj->kvi", r, v) + xy[:, None, :]  # (K, V, 2)
        pts = np.concatenate([w[:-1], w[1:]], axis=1)  # (K-1, 2V, 2)
        pieces.append(point_hulls(pts))
    grow = rho * np.diff(yaw) ** 2 / 8.0
    return np.stack(pieces, axis=1), grow


def disc_depths(tool: Tool, xy: NDArray[np.float64], yaw: NDArray[np.float64], steps: NDArray[np.intp],
                disc: Disc, tol: float = 1e-5) -> NDArray[np.float64]:
    """Penetration depths [m] (len(steps),) into ``disc`` of the tool swept over the ``steps``
    (indices k of the steps k -> k + 1 of ``xy`` (K, 2) / ``yaw`` (K,)), by the construction of
    :func:`tooltransfer.tools.clearance.swept_penetration_depth` vectorized over the steps: each step cut into
    ``n = ceil(|dyaw| / sqrt(8 tol / rho))`` sub-steps, the hull of each convex piece over each
    sub-step grown by ``rho (dyaw / n)^2 / 8``, their union ``U``; the depth is ``R - sd(c, U)``
    (``sd`` negative inside)."""
    verts, rho = tool_geometry(tool)
    dyaw = np.abs(yaw[steps + 1] - yaw[steps])
    n = np.maximum(1, np.ceil(dyaw / np.sqrt(8.0 * tol / rho))).astype(int)
    n[dyaw == 0.0] = 1
    n_max = int(n.max())
    f = np.arange(n_max + 1) / n[:, None]  # (S, n_max + 1) fractions, past 1 for padding
    f = np.minimum(f, 1.0)
    a0, a1 = yaw[steps], yaw[steps + 1]
    p = xy[steps][:, None, :] + f[..., None] * (xy[steps + 1] - xy[steps])[:, None, :]  # (S, n+1, 2)
    r = rot(a0[:, None] + f * (a1 - a0)[:, None])  # (S, n+1, 2, 2)
    grow = rho * (dyaw / n) ** 2 / 8.0
    hulls = []
    for v in verts:
        w = np.einsum("snij,vj->snvi", r, v) + p[:, :, None, :]  # (S, n+1, V, 2)
        pts = np.concatenate([w[:, :-1], w[:, 1:]], axis=2)  # (S, n, 2V, 2)
        h = point_hulls(pts)
        h = np.where(grow[:, None] > 0, shapely.buffer(h, grow[:, None], quad_segs=4), h)
        h[np.arange(n_max)[None, :] >= n[:, None]] = None  # padding beyond each step's sub-steps
        hulls.append(h)
    u = shapely.union_all(np.concatenate(hulls, axis=1), axis=1)
    cx, cy = float(disc.centre[0]), float(disc.centre[1])
    dist = shapely.distance(shapely.boundary(u), shapely.Point(cx, cy))
    sd = np.where(shapely.contains_xy(u, cx, cy), -dist, dist)
    return np.maximum(0.0, disc.radius - sd)


def pose_depth_and_gap(tool: Tool, pose: Pose2D, shape: Disc | shapely.Polygon) -> tuple[float, float]:
    """Penetration depth and clearance [m] of the tool at ``pose`` and ``shape``: for a disc from the
    cached pieces (:func:`disc_depths` on a step of zero length, and the pieces' distance to the
    centre), the same as :func:`tooltransfer.tools.clearance.penetration_depth` / ``clearance``; for a polygon,
    those functions."""
    if not isinstance(shape, Disc):
        from tooltransfer.tools.clearance import clearance, penetration_depth

        return penetration_depth(tool, pose, shape), clearance(tool, pose, shape)
    verts, _ = tool_geometry(tool)
    r = rot(pose.yaw)
    placed = np.array([shapely.Polygon(v @ r.T + (pose.x, pose.y)) for v in verts])  # pieces' sizes differ
    dist = float(shapely.distance(placed, shapely.Point(shape.centre)).min())
    if dist > 0.0:  # the centre outside every piece: sd(c, union) is the smallest distance, exactly
        return max(0.0, shape.radius - dist), max(0.0, dist - shape.radius)
    xy = np.array([[pose.x, pose.y], [pose.x, pose.y]])
    yaw = np.array([pose.yaw, pose.yaw])
    return float(disc_depths(tool, xy, yaw, np.array([0]), shape)[0]), 0.0


def sweep_check(tool: Tool, xy: NDArray[np.float64], yaw: NDArray[np.float64], shape: Disc | shapely.Polygon,
                hulls: tuple[NDArray, NDArray] | None = None, depth_tol: float = 1e-6,
                exact_disc: str = "union", sub_tol: float = 1e-5) -> SweepCheck:
    """Clearance and penetration of the tool swept along ``xy`` (K, 2) [m] / ``yaw`` (K,) [rad]
    against ``shape`` (a :class:`~tooltransfer.tools.objects.Disc` or a shapely polygon). ``hulls`` from
    :func:`step_hulls` may be passed to share them between shapes. Steps reaching into a disc by
    more than ``depth_tol`` [m], or intersecting a polygon, get their exact depth (and ``gap = -depth``);
    elsewhere the depth is ``max(0, -gap)``. For a disc, ``exact_disc`` ``"union"`` measures those
    depths with :func:`disc_depths` (all steps in one vectorized pass); ``"substeps"``: one
    :func:`tooltransfer.tools.clearance.swept_penetration_depth` per step (the same construction, step by step)."""
    h, grow = hulls if hulls is not None else step_hulls(tool, xy, yaw)
    if isinstance(shape, Disc):
        d = shapely.distance(h, shapely.Point(shape.centre)).min(axis=1) - shape.radius - grow
        inside = d < -depth_tol
        if exact_disc == "union" and inside.any():
            idx = np.flatnonzero(inside)
            depth = np.maximum(0.0, -d)
            depth[idx] = disc_depths(tool, xy, yaw, idx, shape, sub_tol)
            d[idx] = np.minimum(d[idx], -depth[idx])
            return SweepCheck(d, depth)
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
