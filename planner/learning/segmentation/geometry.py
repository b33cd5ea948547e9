"""Tool-object geometry for segmentation, vectorized over samples and done in the tool frame.

The object centre ``c`` (world) is brought into the tool frame of each sample,
``c_T = R(yaw)^T (c - p)`` with the tool pose ``(p, yaw)``; there the outline and the faces are
fixed, so a distance to them is a distance to a few static segments.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.tools.model import Face, Tool


def to_tool_frame(points: ArrayLike, pose: NDArray[np.float64]) -> NDArray[np.float64]:
    """World points (N, 2) or one point (2,) [m] in the tool frames of ``pose`` (N, 3) -> (N, 2)."""
    d = np.asarray(points, dtype=np.float64) - pose[:, :2]
    cs, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    return np.column_stack([cs * d[:, 0] + sn * d[:, 1], -sn * d[:, 0] + cs * d[:, 1]])


def to_world(points: NDArray[np.float64], pose: NDArray[np.float64]) -> NDArray[np.float64]:
    """Tool-frame points (N, 2) at poses (N, 3) in the world (N, 2) [m]."""
    cs, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    return pose[:, :2] + np.column_stack([cs * points[:, 0] - sn * points[:, 1], sn * points[:, 0] + cs * points[:, 1]])


def nearest_on_segments(
    q: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """For points ``q`` (N, 2) and segments ``a``-``b`` (S, 2): distance (N,) [m] to the nearest
    segment and the nearest point (N, 2)."""
    ab = b - a  # (S, 2)
    s = np.einsum("nsk,sk->ns", q[:, None, :] - a[None], ab) / np.maximum(np.einsum("sk,sk->s", ab, ab), 1e-18)
    p = a[None] + np.clip(s, 0.0, 1.0)[..., None] * ab[None]  # (N, S, 2)
    d = np.linalg.norm(q[:, None, :] - p, axis=2)
    j = np.argmin(d, axis=1)
    idx = np.arange(q.shape[0])
    return d[idx, j], p[idx, j]


class ToolGeometry:
    """A tool's outline edges and contact segments in its frame, for distance queries.

    Args:
        tool: the tool; radius: the disc object's radius [m].
    """

    def __init__(self, tool: Tool, radius: float) -> None:
        self.tool, self.radius = tool, radius
        xy = np.asarray(tool.outline.exterior.coords)[:-1]
        self._a, self._b = xy, np.roll(xy, -1, axis=0)
        self._outline = tool.outline

    def outline_gap(self, c_tool: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Gap (N,) [m] between the outline and the disc centred at ``c_tool`` (N, 2) (tool frame;
        negative: overlap, the centre inside counts as -radius at least) and the nearest outline
        point (N, 2)."""
        d, p = nearest_on_segments(c_tool, self._a, self._b)
        inside = _inside(c_tool, self._a, self._b)
        return np.where(inside, -d, d) - self.radius, p

    def face_gap(self, face: Face, c_tool: NDArray[np.float64]) -> NDArray[np.float64]:
        """Gap (N,) [m] between ``face``'s contact segment and the disc at ``c_tool`` (N, 2) (tool
        frame); inf where the centre is behind the face's line (the face cannot touch it)."""
        a, b = face.contact_segment()
        d, _ = nearest_on_segments(c_tool, a[None], b[None])
        front = (c_tool - a) @ face.normal > 0.0
        return np.where(front, d - self.radius, np.inf)


def _inside(q: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Even-odd rule: which points ``q`` (N, 2) lie inside the polygon with edges ``a``-``b``."""
    y = q[:, 1:2]
    cond = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
        x_cross = a[None, :, 0] + (y - a[None, :, 1]) * slope
    return np.count_nonzero(cond & (q[:, 0:1] < x_cross), axis=1) % 2 == 1


def table_poses(q: ArrayLike, a_t: float, base_xy: ArrayLike = (0.0, 0.0), base_yaw: float = np.pi / 2,
                table_height: float = 0.0) -> NDArray[np.float64]:
    """Forward kinematics of the Omni (DH Table I, :func:`tooltransfer.tools.omni.ik.table_pose`) vectorized: the
    planar tool poses (N, 3) (x, y [m], heading [rad]) of joints ``q`` (N, 3) [rad] on a platform
    with tool length ``a_t`` [m], base at ``base_xy`` [m] turned by ``base_yaw`` [rad], and
    ``table_height`` [m] (it moves the tool up or down, not across)."""
    from tooltransfer.tools.omni.dh import D_TOOL, L1, L2, THETA_TOOL

    del table_height  # the pushing plane's height does not move the tool's projection on it
    qv = np.asarray(q, dtype=np.float64).reshape(-1, 3)
    q1, q2, q3 = qv[:, 0], qv[:, 1], qv[:, 2]
    u = L1 * np.cos(q2) + L2 * np.cos(q2 + q3) + a_t * np.cos(q2 + q3 + THETA_TOOL)  # along the arm
    bx = u * np.cos(q1) - D_TOOL * np.sin(q1)
    by = u * np.sin(q1) + D_TOOL * np.cos(q1)
    c, s = np.cos(base_yaw), np.sin(base_yaw)
    bxy = np.asarray(base_xy, dtype=np.float64)
    return np.column_stack([c * bx - s * by + bxy[0], s * bx + c * by + bxy[1], base_yaw + q1 - np.pi / 2])
