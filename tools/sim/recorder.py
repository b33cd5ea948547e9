"""Turn the sensor rows of an execution's physics steps into an :class:`Execution`: sample the
streams at their rates, attribute each tool-object contact to a tool face, group contacts into
events.

Contact is MuJoCo's: a tool piece and the puck touch at a step when the collision detection
finds them penetrating (the only state in which they exchange force). Pushed against the table's
friction (0.06 N), the puck separates from the face and touches it again every few steps, by
micrometres (14 um at most in the straight push of the tests), so the contacts of a push come in
bursts; breaks shorter than :data:`CONTACT_GAP` are bridged into one event, and a tool sample is
in contact when it lies inside an event.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.sim.execution import CONTACT_GAP, ContactEvent, Execution, Rates
from tooltransfer.tools.sim.model import SensorRows

#: A contact point within this distance [m] of a face's segment (tool frame) is on that face.
FACE_TOL = 0.001


def sample_steps(step0: int, n: int, dt: float, rate: float) -> NDArray[np.intp]:
    """Indices (into ``0 .. n-1``) of the physics steps ``step0 + i`` sampled at ``rate`` [Hz]: the
    first step at or after each multiple of ``1 / rate`` on the clock ``t = step * dt`` [s]."""
    if rate * dt > 1.0 + 1e-9:
        raise InputError("rates", f"rates of at most the physics rate {1.0 / dt:g} Hz", f"{rate:g} Hz")
    j = step0 + np.arange(-1, n)
    k = np.floor(j * (dt * rate) + 1e-9)
    take = k[1:] > k[:-1]
    if step0 == 0 and n > 0:
        take[0] = True
    return np.flatnonzero(take)


def _segment_distance(p: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance (n,) [m] of points ``p`` (n, 2) from the segment ``ab``."""
    e = b - a
    s = np.clip(((p - a) @ e) / float(e @ e), 0.0, 1.0)
    return np.hypot(*(p - a - s[:, None] * e).T)


def face_labels(tool: Tool, points: NDArray[np.float64], pose: NDArray[np.float64]) -> NDArray[np.intp]:
    """Index into ``tool.faces`` of the face nearest each world point (n, 2) [m] seen from the tool
    poses (n, 3), or -1 when no face lies within :data:`FACE_TOL`."""
    c, s = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    d = points - pose[:, :2]
    local = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
    if not len(local):
        return np.zeros(0, dtype=np.intp)
    dist = np.column_stack([_segment_distance(local, f.start, f.end) for f in tool.faces])
    best = np.argmin(dist, axis=1)
    return np.where(dist[np.arange(len(best)), best] <= FACE_TOL, best, -1)


def _events(tool: Tool, t: NDArray[np.float64], touching: NDArray[np.bool_], piece: NDArray[np.intp],
            face: NDArray[np.intp], depth: NDArray[np.float64]) -> tuple[tuple[ContactEvent, ...], NDArray[np.bool_]]:
    """The contact events of the steps at times ``t`` (n,) [s] and whether each step lies in one."""
    inside = np.zeros(len(t), dtype=bool)
    idx = np.flatnonzero(touching)
    if not idx.size:
        return (), inside
    groups = np.split(idx, np.flatnonzero(np.diff(t[idx]) > CONTACT_GAP) + 1)
    out = []
    for g in groups:
        inside[g[0] : g[-1] + 1] = True
        faces = np.bincount(face[g] + 1, minlength=len(tool.faces) + 1)  # slot 0: off every face
        f = int(np.argmax(faces)) - 1
        out.append(ContactEvent(
            float(t[g[0]]), float(t[g[-1]]), int(np.argmax(np.bincount(piece[g]))), float(depth[g].max()),
            tool.faces[f].name if f >= 0 else None,
        ))
    return tuple(out), inside


def record(tool: Tool, rows: SensorRows, step0: int, dt: float, q_ref: NDArray[np.float64], rates: Rates) -> Execution:
    """The recording of ``n`` physics steps from global step ``step0`` (time ``step0 * dt`` [s]).

    Args:
        tool: the tool on the platform (its faces name the contacts).
        rows: the sensor data of the ``n`` steps (the state at the start of each).
        step0: global index of the first step; dt: physics step [s].
        q_ref: shape (n, 3), the joint reference of each step [rad].
        rates: recording rates.
    """
    n = len(rows.joints)
    t = (step0 + np.arange(n)) * dt
    tool_pose = np.column_stack([rows.tcp[:, :2], np.arctan2(rows.tool_x[:, 1], rows.tool_x[:, 0])])
    found = rows.touch_found > 0
    touching = found.any(axis=1)
    dist = np.where(found, rows.touch_dist, np.inf)
    piece = np.argmin(dist, axis=1)
    depth = np.where(touching, np.maximum(-dist[np.arange(n), piece], 0.0), 0.0)
    face = np.full(n, -1, dtype=np.intp)
    if touching.any():
        at = rows.touch_pos[np.arange(n), piece, :2]
        face[touching] = face_labels(tool, at[touching], tool_pose[touching])
    events, inside = _events(tool, t, touching, piece, face, depth)
    io = sample_steps(step0, n, dt, rates.object_hz)
    it = sample_steps(step0, n, dt, rates.tool_hz)
    w, z = rows.puck_quat[io, 0], rows.puck_quat[io, 3]
    return Execution(
        t_object=t[io],
        object_xy=rows.puck_pos[io, :2].copy(),
        object_yaw=2.0 * np.arctan2(z, w),
        t_tool=t[it],
        tool_pose=tool_pose[it],
        joints=rows.joints[it].copy(),
        joints_ref=q_ref[it].copy(),
        contact=inside[it],
        penetration=depth[it],
        contacts=events,
    )
