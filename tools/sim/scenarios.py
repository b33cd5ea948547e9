"""Scripted pushes on the simulated platform, shared by the tests, the benchmark and the example:
a straight push with one face, and a sideways sweep that shows the tool's heading turning with q1
and the puck drifting along the face.

Each places the tool with :func:`tools.contact_on_platform` (the face touching the puck at the
heading the Omni imposes there), backs it off, and moves its tool centre point along a straight
line with a minimum-jerk profile through :meth:`SimPlatform.execute_tool_path`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.contact import contact_on_platform
from tooltransfer.tools.sim.execution import Execution, Rates
from tooltransfer.tools.sim.platform import SimPlatform
from tooltransfer.validation import check_array, check_positive

#: Tool path samples per second of a scripted push.
SAMPLES_PER_S = 100


@dataclass(frozen=True)
class Push:
    """A scripted push and what it recorded.

    Attributes:
        object_start: shape (2,), the puck's start [m].
        t: shape (T,), times of the tool path [s]; tool_path: shape (T, 2), the commanded tool
            centre point [m].
        execution: the recording.
    """

    object_start: NDArray[np.float64]
    t: NDArray[np.float64]
    tool_path: NDArray[np.float64]
    execution: Execution

    @property
    def heading_change(self) -> float:
        """Turn of the tool's heading from the first to the last tool sample [rad]."""
        yaw = self.execution.tool_pose[:, 2]
        return float(yaw[-1] - yaw[0])

    @property
    def object_motion(self) -> NDArray[np.float64]:
        """The puck's displacement (2,) [m] from its start to the last sample."""
        return self.execution.object_xy[-1] - self.object_start


def _min_jerk(n: int) -> NDArray[np.float64]:
    s = np.linspace(0.0, 1.0, n)
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def line_push(
    sim: SimPlatform, object_xy: ArrayLike, face: str, direction: float, stroke: float, *,
    offset: ArrayLike = (0.0, 0.0), duration: float = 4.0, rates: Rates | None = None,
) -> Push:
    """Reset with ``face`` touching the puck at ``object_xy`` (2,) [m] to push it along ``direction``
    [rad] (at the heading the Omni has there), moved by ``offset`` (2,) [m] (e.g. a gap behind the
    puck), then move the tool by ``stroke`` [m] along ``direction`` in ``duration`` [s].

    Raises:
        InputError: the contact pose or the path leaves the Omni's reach.
    """
    obj = check_array(object_xy, "object_xy", shape=(2,))
    off = check_array(offset, "offset", shape=(2,))
    dur = check_positive(duration, "duration")
    placed = contact_on_platform(sim.tool, face, obj, float(direction), sim.platform)
    if placed.contact is None:
        raise InputError("object_xy", f"a puck the Omni can reach with face {face!r}", placed.ik.detail)
    start = placed.contact.pose.position + off
    n = max(3, round(dur * SAMPLES_PER_S) + 1)
    t = np.linspace(0.0, dur, n)
    path = start + _min_jerk(n)[:, None] * (stroke * np.array([np.cos(direction), np.sin(direction)]))
    sim.reset(obj, tool_xy=start)
    return Push(obj, t, path, sim.execute_tool_path(t, path, rates=rates))


def forward_push(sim: SimPlatform, object_xy: ArrayLike = (0.0, 0.15), *, distance: float = 0.06,
                 gap: float = 0.01, duration: float = 4.0, rates: Rates | None = None) -> Push:
    """The upper face ``gap`` [m] behind the puck, then straight forward (+y) by ``gap + distance``:
    the ideal kinematic push moves the puck ``distance`` straight forward."""
    return line_push(sim, object_xy, "upper", np.pi / 2, gap + distance, offset=(0.0, -gap),
                     duration=duration, rates=rates)


def sideways_sweep(sim: SimPlatform, object_xy: ArrayLike = (0.04, 0.16), *, sweep: float = 0.08,
                   gap: float = 0.005, duration: float = 5.0, rates: Rates | None = None) -> Push:
    """The left face ``gap`` [m] right of the puck, then a sweep of ``sweep`` [m] to the left (-x):
    the heading turns with q1 on the way, and the puck drifts along the face."""
    return line_push(sim, object_xy, "left", np.pi, sweep, offset=(gap, 0.0), duration=duration, rates=rates)
