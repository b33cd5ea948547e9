"""One demonstration's tracks smoothed and measured against the tool, what every pass of the segmentation reads.

The encoders' tool track is smoothed with a cubic Savitzky-Golay filter and differentiated, the camera's object
track with a quadratic one; each face's gap to the object and its velocity along its outward normal follow.
:class:`Tracks` also answers the segmentation's geometric questions: where the object rests (camera samples
since its last move, projected onto the tool's outline after a contact), whether a face is the part of the tool
that touches, and when the outline reaches a resting object. The method is in
:mod:`tooltransfer.planner.learning.segmentation.core`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from tooltransfer.planner.learning.segmentation.geometry import (
    ToolGeometry,
    nearest_on_segments,
    to_tool_frame,
    to_world,
)
from tooltransfer.planner.learning.segmentation.rest import camera_noise, still_tail
from tooltransfer.problems.dataset import Demonstration
from tooltransfer.tools.model import Tool

__all__ = ["Tracks", "pose_at"]


def _crossing(t: NDArray[np.float64], g: NDArray[np.float64]) -> float | None:
    """First time the gap ``g`` (K,) falls from above 0 to 0 or below, interpolated linearly."""
    hit = np.flatnonzero((g[1:] <= 0.0) & (g[:-1] > 0.0))
    if hit.size == 0:
        return None
    k = int(hit[0]) + 1
    return float(t[k - 1] + (t[k] - t[k - 1]) * g[k - 1] / (g[k - 1] - g[k]))


def _odd_window(t: NDArray[np.float64], window: float) -> int:
    """Odd number of samples spanning about ``window`` [s] (at least 5)."""
    return max(5, round(window / float(np.median(np.diff(t)))) // 2 * 2 + 1)


def _normal_velocity(
    vel: NDArray[np.float64], pose: NDArray[np.float64], normal: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Tool velocity (N,) [m/s] along a face's outward ``normal`` (tool frame) turned into the world."""
    cs, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    return vel[:, 0] * (cs * normal[0] - sn * normal[1]) + vel[:, 1] * (sn * normal[0] + cs * normal[1])


def pose_at(t: NDArray[np.float64], pose: NDArray[np.float64], when: float) -> NDArray[np.float64]:
    """Tool pose (1, 3) interpolated at time ``when`` [s] (heading unwrapped)."""
    return np.array([[np.interp(when, t, pose[:, j]) for j in range(3)]])


@dataclass(frozen=True)
class Tracks:
    """One demonstration's smoothed tracks, what every pass of
    :func:`tooltransfer.planner.learning.segmentation.core.segment` reads: tool times ``t`` (N,) [s] with the
    smoothed pose (N, 3) [m, rad] and velocity (N, 3), camera times ``t_o`` (M,) [s] with the smoothed object
    centre ``obj`` (M, 2) [m] and ``c`` (N, 2) [m] at the tool's times; per face (columns in ``names`` order)
    the gap to the object ``gaps`` (N, F) [m] and the velocity along the face's normal ``v_n`` (N, F) [m/s];
    the camera noise ``sigma`` [m]."""

    demo: Demonstration
    tool: Tool
    geo: ToolGeometry
    radius: float
    names: list[str]
    t: NDArray[np.float64]
    t_o: NDArray[np.float64]
    dt: float
    pose: NDArray[np.float64]
    obj: NDArray[np.float64]
    c: NDArray[np.float64]
    gaps: NDArray[np.float64]
    v_n: NDArray[np.float64]
    sigma: float

    @classmethod
    def smoothed(cls, demo: Demonstration, tool: Tool, radius: float, smooth: float, tool_smooth: float) -> Tracks:
        """Smooth the recordings (Savitzky-Golay: cubic over ``tool_smooth`` [s] for the encoders,
        quadratic over ``smooth`` [s] for the camera) and measure each face against the object."""
        t, t_o = demo.t_tool, demo.t_object
        raw = demo.tool_pose.copy()
        raw[:, 2] = np.unwrap(raw[:, 2])
        dt = float(np.median(np.diff(t)))
        pose = savgol_filter(raw, _odd_window(t, tool_smooth), 3, axis=0, mode="interp")
        vel = savgol_filter(raw, _odd_window(t, tool_smooth), 3, deriv=1, delta=dt, axis=0, mode="interp")
        obj = savgol_filter(demo.object_xy, _odd_window(t_o, smooth), 2, axis=0, mode="interp")
        c = np.column_stack([np.interp(t, t_o, obj[:, j]) for j in range(2)])
        geo = ToolGeometry(tool, radius)
        names = list(tool.face_names)
        c_tool = to_tool_frame(c, pose)
        gaps = np.column_stack([geo.face_gap(tool.face(n), c_tool) for n in names])
        v_n = np.column_stack([_normal_velocity(vel, pose, tool.face(n).normal) for n in names])
        return cls(demo, tool, geo, radius, names, t, t_o, dt, pose, obj, c, gaps, v_n, camera_noise(demo.object_xy))

    def rest(self, t0: float, t1: float, after: NDArray[np.float64] | None,
             fallback: NDArray[np.float64] | None = None) -> NDArray[np.float64] | None:
        """Rest position (2,) from the camera samples in [t0, t1], projected onto the curve one
        radius off the outline at pose ``after`` (1, 3) when the rest follows a contact. With
        fewer than 3 samples: None, or with a ``fallback`` pose the smoothed track at ``t0``
        projected onto the outline at that pose. Only the samples after the object's last move count
        (:func:`tooltransfer.planner.learning.segmentation.rest.still_tail`), so a push not found does not spoil the
        next rest."""
        t_o, obj, demo = self.t_o, self.obj, self.demo
        idx = np.flatnonzero((t_o >= t0) & (t_o <= t1))
        if idx.size >= 3:
            idx, whole = still_tail(demo.object_xy, idx, self.sigma)
            p = demo.object_xy[idx].mean(axis=0)
            if not whole:  # the object moved after t0 (a push not found): no longer where it was left
                after = None
        elif fallback is not None:
            p, after = np.array([np.interp(t0, t_o, obj[:, 0]), np.interp(t0, t_o, obj[:, 1])]), fallback
        else:
            return None
        if after is None:
            return p
        q = to_tool_frame(p, after)
        _, near = self.geo.outline_gap(q)
        u = q - near
        n = float(np.hypot(*u[0]))
        return p if n == 0.0 else to_world(near + self.radius * u / n, after)[0]

    def touches_face(self, p: NDArray[np.float64], when: float, j: int, face_tol: float) -> bool:
        """Whether the outline point nearest the object at ``p`` (2,) lies on face ``j`` (within
        ``face_tol`` [m]) with the tool at its pose at time ``when`` [s]."""
        _, near = self.geo.outline_gap(to_tool_frame(p, pose_at(self.t, self.pose, when)))
        a, b = self.tool.face(self.names[j]).contact_segment()
        return float(nearest_on_segments(near, a[None], b[None])[0][0]) <= face_tol

    def start_of(self, before: NDArray[np.float64], s0: int, e0: int) -> float | None:
        """When [s] the outline first reaches the object resting at ``before`` (2,) during the
        stroke of samples ``s0..e0`` (None if it never does)."""
        seg = slice(s0, e0 + 1)
        return _crossing(self.t[seg], self.geo.outline_gap(to_tool_frame(before, self.pose[seg]))[0])
