"""The tool body against the obstacles along the whole plan.

OE condensing keeps the *object* ``safety_margin`` away from the obstacles; the tool that pushes it
is large (tens of millimetres) and can sweep over an obstacle while the object stays clear. This
check measures, with shapely, the distance between the tool outline at every sample of the plan and
every obstacle: a plan whose tool overlaps an obstacle is not executable (on the platform the tool
would hit it) and is reported infeasible with the place and time.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc

#: Least distance [m] between the tool's outline and every obstacle that a solved plan keeps, along its
#: pushes and its switches: the closed loop's safety envelope
#: (:mod:`tooltransfer.planner.execution.envelope`) refuses any command that comes closer, so a plan
#: passing nearer could be executed open loop only.
TOOL_MARGIN = 0.00025


@dataclass(frozen=True)
class ToolClearance:
    """Least tool-obstacle distance [m] (inf without obstacles) and where it occurs: sample index,
    obstacle index (-1 without obstacles)."""

    distance: float
    sample: int
    obstacle: int


def tool_obstacle_clearance(tool: Tool, tool_pose: NDArray[np.float64],
                            obstacles: Sequence[Disc | shapely.Polygon]) -> ToolClearance:
    """Distance between the tool outline at each pose of ``tool_pose`` (K, 3) (x, y [m], yaw [rad],
    world frame) and each obstacle; 0 where they overlap. Samples without a pose (NaN: outside the
    Omni's reach, reported by the joint-limit check) are skipped."""
    ok = np.flatnonzero(np.all(np.isfinite(tool_pose), axis=1))
    if not obstacles or ok.size == 0:
        return ToolClearance(float("inf"), -1, -1)
    best = ToolClearance(float("inf"), -1, -1)
    for j, d in enumerate(outline_distances(tool, tool_pose[ok], obstacles)):
        k = int(np.argmin(d))
        if d[k] < best.distance:
            best = ToolClearance(float(d[k]), int(ok[k]), j)
    return best


def outline_distances(tool: Tool, tool_pose: NDArray[np.float64],
                      obstacles: Sequence[Disc | shapely.Polygon]) -> NDArray[np.float64]:
    """Distance [m] (len(obstacles), K) between the tool outline at each pose of ``tool_pose`` (K, 3) (x, y [m],
    yaw [rad], world frame, all finite) and each obstacle; 0 where they overlap."""
    ring = np.asarray(tool.outline.exterior.coords)[:-1]
    c, s = np.cos(tool_pose[:, 2]), np.sin(tool_pose[:, 2])
    x = tool_pose[:, None, 0] + c[:, None] * ring[None, :, 0] - s[:, None] * ring[None, :, 1]
    y = tool_pose[:, None, 1] + s[:, None] * ring[None, :, 0] + c[:, None] * ring[None, :, 1]
    polys = shapely.polygons(np.stack([x, y], axis=-1))
    out = np.empty((len(obstacles), len(tool_pose)))
    for j, o in enumerate(obstacles):
        out[j] = (np.maximum(shapely.distance(polys, shapely.Point(o.centre)) - o.radius, 0.0)
                  if isinstance(o, Disc) else shapely.distance(polys, o))
    return out
