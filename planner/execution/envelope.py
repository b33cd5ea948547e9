"""The safety envelope every tool command of the closed loop is checked against before it is sent.

The envelope uses only what the loop knows for certain, independently of the plan and of the
camera: the obstacles (grown by :data:`ENVELOPE_MARGIN` against the tool's outline), the Omni's
reach and joint limits (:func:`tooltransfer.tools.omni.ik.joint_path`) and the table's bounds. A command
``tool_pose`` (K, 3) is checked along the straight pieces from the tool's reported pose through
every commanded sample, densely sampled (at most :data:`ENVELOPE_STEP` apart), with the heading the
Omni's waist imposes there (the yaw a plant may take as a check only). The first violation is named
(the check, the sample's position); :class:`tooltransfer.planner.execution.guarded_plant.GuardedPlant`
never sends a command that has one.

The tool's margin is its own, smaller than the object's ``safety_margin``: the plans keep the object
that margin from the obstacles and the tool outline only this one (``tool_obstacle_clearance_min`` and
``switch_obstacle_clearance_min`` at least :data:`ENVELOPE_MARGIN`, a hard check of every solved plan), and
tools pass a few millimetres from an obstacle in plans the loop executes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN, tool_obstacle_clearance
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Obstacle
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.omni.platform import OmniPlatform

#: Least distance [m] between the tool's outline and any obstacle along a command (the margin every
#: solved plan keeps: :data:`~tooltransfer.planner.planning.tool_clearance.TOOL_MARGIN`).
ENVELOPE_MARGIN = TOOL_MARGIN
#: Largest spacing [m] of the samples the envelope checks along a command.
ENVELOPE_STEP = 5e-4
#: The table's bounds ``(x_min, x_max, y_min, y_max)`` [m] in the world frame: the simulated
#: platform's 2 m x 2 m table about the origin (:mod:`tooltransfer.tools.sim.mjcf`).
TABLE_BOUNDS = (-1.0, 1.0, -1.0, 1.0)


def densify(points: ArrayLike, step: float = ENVELOPE_STEP) -> NDArray[np.float64]:
    """The polyline ``points`` (K, 2) [m] with each piece cut into pieces at most ``step`` [m] long;
    (M, 2), the given points among them."""
    p = np.asarray(points, dtype=np.float64)
    if len(p) < 2:
        return p.copy()
    out = [p[:1]]
    for a, b in pairwise(p):
        n = max(1, int(np.ceil(float(np.hypot(*(b - a))) / step)))
        out.append(a + np.outer(np.arange(1, n + 1) / n, b - a))
    return np.vstack(out)


@dataclass(frozen=True)
class SafetyEnvelope:
    """Where the tool may be commanded (module docstring).

    Attributes:
        tool: the tool the Omni carries; platform: the Omni (reach, joint limits, heading).
        obstacles: discs and polygons [m]; margin: least tool-outline distance to them [m].
        table: ``(x_min, x_max, y_min, y_max)`` [m] the whole tool outline stays within.
        step: largest spacing [m] of the checked samples.
    """

    tool: Tool
    platform: OmniPlatform
    obstacles: tuple[Obstacle, ...] = ()
    margin: float = ENVELOPE_MARGIN
    table: tuple[float, float, float, float] = TABLE_BOUNDS
    step: float = ENVELOPE_STEP

    @classmethod
    def of(cls, setting: Setting, margin: float = ENVELOPE_MARGIN) -> SafetyEnvelope:
        """The envelope of a planning setting (its tool, Omni and obstacles)."""
        return cls(setting.tool, setting.platform, tuple(setting.obstacles), margin)

    def violation(self, start: ArrayLike | None, tool_pose: ArrayLike) -> str | None:
        """None when the command is safe, else what it violates and where. ``start``: the tool's
        reported pose (3,) or None (unknown: the check starts at the first sample); ``tool_pose``:
        the commanded poses (K, 3) [m, m, rad]."""
        pose = np.asarray(tool_pose, dtype=np.float64)
        if pose.ndim != 2 or pose.shape[1] != 3 or len(pose) == 0:
            return f"a command of shape {pose.shape} (expected (K, 3))"
        if not np.all(np.isfinite(pose[:, :2])):
            return "a command with a non-finite position"
        xy = pose[:, :2]
        if start is not None:
            s = np.asarray(start, dtype=np.float64)
            if s.shape == (3,) and np.all(np.isfinite(s)):
                xy = np.vstack([s[:2], xy])
        dense = densify(xy, self.step)
        jp = joint_path(self.platform, dense)
        bad = np.flatnonzero(jp.refused)
        if bad.size:
            return f"outside the Omni's reach or joint limits at {_at(dense[bad[0]])}"
        if not np.all(np.isfinite(pose[:, 2])):
            return "a command with a non-finite heading"
        poses = np.column_stack([dense, jp.heading])
        off = self._off_table(poses)
        if off is not None:
            return f"the tool outline off the table at {_at(dense[off])}"
        if self.obstacles:
            near = tool_obstacle_clearance(self.tool, poses, self.obstacles)
            if near.distance < self.margin:
                return (f"the tool outline {1e3 * near.distance:.2f} mm from obstacles[{near.obstacle}] "
                        f"(less than {1e3 * self.margin:.2f} mm) at {_at(dense[near.sample])}")
        return None

    def _off_table(self, poses: NDArray[np.float64]) -> int | None:
        ring = np.asarray(self.tool.outline.exterior.coords)[:-1]
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        x = poses[:, None, 0] + c[:, None] * ring[None, :, 0] - s[:, None] * ring[None, :, 1]
        y = poses[:, None, 1] + s[:, None] * ring[None, :, 0] + c[:, None] * ring[None, :, 1]
        x0, x1, y0, y1 = self.table
        out = np.flatnonzero((x.min(axis=1) < x0) | (x.max(axis=1) > x1) | (y.min(axis=1) < y0) | (y.max(axis=1) > y1))
        return int(out[0]) if out.size else None


def _at(p: Sequence[float] | NDArray[np.float64]) -> str:
    return f"{np.round(np.asarray(p, dtype=float), 4).tolist()} m"
