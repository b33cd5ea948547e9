"""The simulated Omni platform: run joint or tool paths with PD tracking and record what happens.

:class:`SimPlatform` is stateful, so an operator can execute in chunks, look at the puck
(:meth:`SimPlatform.observe`) and correct. Recordings (:class:`Execution`) come at requested rates:
the object centre as a camera sees it, the tool pose and joints as the encoders give them, plus
the tool-object contact events.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from dmp.errors import InputError
from dmp.validation import check_array, check_time
from tools.model import Tool
from tools.objects import Obstacle
from tools.omni.ik import joint_path
from tools.omni.platform import OmniPlatform
from tools.sim.mjcf import PUCK_HALF_HEIGHT, SimParams, build_mjcf

CONTACT_GAP = 0.02
"""Contact breaks shorter than this [s] (the puck chattering on the face) stay one event."""


@dataclass(frozen=True)
class Rates:
    """Recording rates [Hz]: ``object_hz`` (camera), ``tool_hz`` (encoders)."""

    object_hz: float = 30.0
    tool_hz: float = 200.0


@dataclass(frozen=True)
class ContactEvent:
    """A stretch of tool-object contact: ``t_start``, ``t_end`` [s], the tool piece touching most,
    and the largest penetration [m]."""

    t_start: float
    t_end: float
    piece: int
    max_penetration: float


@dataclass(frozen=True)
class Execution:
    """What an execution recorded (times on the platform's clock [s]).

    Attributes:
        t_object (M,), object_xy (M, 2) [m], object_yaw (M,) [rad];
        t_tool (N,), tool_pose (N, 3) (x, y [m], yaw [rad]), joints (N, 3) [rad],
        joints_ref (N, 3) [rad], contact (N,) bool; contacts: the contact events.
    """

    t_object: NDArray[np.float64]
    object_xy: NDArray[np.float64]
    object_yaw: NDArray[np.float64]
    t_tool: NDArray[np.float64]
    tool_pose: NDArray[np.float64]
    joints: NDArray[np.float64]
    joints_ref: NDArray[np.float64]
    contact: NDArray[np.bool_]
    contacts: tuple[ContactEvent, ...] = field(default=())

    @staticmethod
    def concat(parts: Sequence[Execution]) -> Execution:
        """One recording of consecutive executions."""
        cat = np.concatenate
        return Execution(
            cat([p.t_object for p in parts]), cat([p.object_xy for p in parts]), cat([p.object_yaw for p in parts]),
            cat([p.t_tool for p in parts]), cat([p.tool_pose for p in parts]), cat([p.joints for p in parts]),
            cat([p.joints_ref for p in parts]), cat([p.contact for p in parts]),
            tuple(e for p in parts for e in p.contacts),
        )

    @property
    def tracking_error(self) -> float:
        """Largest joint tracking error [rad]."""
        return float(np.abs(self.joints - self.joints_ref).max()) if self.joints.size else 0.0


class SimPlatform:
    """The Omni carrying ``tool`` with the puck (and ``obstacles``) in MuJoCo.

    Args:
        tool: the tool; platform: the Omni (default: :class:`OmniPlatform` with the tool's a_t);
        obstacles: discs and convex polygons on the table; params: physical parameters.
    """

    def __init__(
        self, tool: Tool, platform: OmniPlatform | None = None, obstacles: Sequence[Obstacle] = (),
        params: SimParams | None = None,
    ) -> None:
        self.tool = tool
        self.platform = platform or OmniPlatform(a_t=tool.a_t)
        self.params = params or SimParams()
        self.xml = build_mjcf(tool, self.platform, obstacles, self.params)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._q = np.array([m.joint(n).qposadr[0] for n in ("q1", "q2", "q3")])
        self._qd = np.array([m.joint(n).dofadr[0] for n in ("q1", "q2", "q3")])
        self._lvl = np.array([m.joint(n).qposadr[0] for n in ("level2", "level3")])
        self._puck = m.joint("puck").qposadr[0]
        self._puck_geom = m.geom("puck").id
        self._tool_geoms = {m.geom(f"tool_piece{i}").id: i for i in range(len(tool.convex_pieces))}
        self._tcp, self._plane = m.body("tcp_row").id, m.body("tool_plane").id
        self.time = 0.0

    # ------------------------------------------------------------------ state
    def reset(self, object_xy: ArrayLike, q0: ArrayLike | None = None, tool_xy: ArrayLike | None = None) -> None:
        """Put the puck at ``object_xy`` (2,) [m] at rest and the arm at ``q0`` (3,) [rad] (or where
        its tool centre point is at ``tool_xy`` (2,) [m]); the clock restarts at 0."""
        xy = check_array(object_xy, "object_xy", shape=(2,))
        if q0 is None:
            if tool_xy is None:
                raise InputError("q0", "joint angles or a tool_xy to start from")
            jp = joint_path(self.platform, check_array(tool_xy, "tool_xy", shape=(2,))[None])
            if not np.isfinite(jp.violation[0]) or jp.violation[0] > 0:
                raise InputError("tool_xy", "a point the Omni reaches within its joint limits", list(xy))
            q0 = jp.q[0]
        q = check_array(q0, "q0", shape=(3,))
        d = self.data
        mujoco.mj_resetData(self.model, d)
        d.qpos[self._puck : self._puck + 7] = [xy[0], xy[1], PUCK_HALF_HEIGHT + 1e-4, 1, 0, 0, 0]
        d.qpos[self._q] = q
        d.qpos[self._lvl] = -q[1:]
        d.ctrl[:3], d.ctrl[3:] = q, 0.0
        mujoco.mj_forward(self.model, d)
        self.time = 0.0

    def observe(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Current object centre (2,) [m] and tool pose (3,) (x, y [m], yaw [rad])."""
        return self.data.qpos[self._puck : self._puck + 2].copy(), self._tool_pose()

    def _tool_pose(self) -> NDArray[np.float64]:
        d = self.data
        xm = d.xmat[self._plane].reshape(3, 3)
        return np.array([d.xpos[self._tcp, 0], d.xpos[self._tcp, 1], np.arctan2(xm[1, 0], xm[0, 0])])

    def _touch(self) -> tuple[int, float]:
        """Tool piece in contact with the puck (-1 if none) and the deepest penetration [m]."""
        d = self.data
        piece, depth = -1, 0.0
        for i in range(d.ncon):
            c = d.contact[i]
            other = c.geom2 if c.geom1 == self._puck_geom else c.geom1 if c.geom2 == self._puck_geom else -1
            if other in self._tool_geoms and -c.dist >= depth:
                piece, depth = self._tool_geoms[other], max(depth, -c.dist)
        return piece, depth

    # ------------------------------------------------------------------ running
    def execute(self, t: ArrayLike, q: ArrayLike, qd: ArrayLike | None = None, rates: Rates | None = None) -> Execution:
        """Track the joint path ``q`` (T, 3) [rad] over times ``t`` (T,) [s] (relative; linear
        interpolation between samples, velocities by differences unless ``qd`` is given) with the
        PD actuators, continuing from the current state; returns the recording."""
        tt = check_time(t, "t", min_len=2)
        qq = check_array(q, "q", shape=(tt.size, 3))
        qv = np.gradient(qq, tt, axis=0) if qd is None else check_array(qd, "qd", shape=(tt.size, 3))
        r = rates or Rates()
        dt = self.model.opt.timestep
        n = round((tt[-1] - tt[0]) / dt)
        ts = tt[0] + dt * np.arange(1, n + 1)
        q_ref = np.column_stack([np.interp(ts, tt, qq[:, j]) for j in range(3)])
        qd_ref = np.column_stack([np.interp(ts, tt, qv[:, j]) for j in range(3)])
        obj_every = max(1, round(1.0 / (r.object_hz * dt)))
        tool_every = max(1, round(1.0 / (r.tool_hz * dt)))
        rec_o: list[tuple[float, float, float, float]] = []
        rec_t: list[NDArray[np.float64]] = []
        events: list[ContactEvent] = []
        open_ev: list[float] | None = None
        m, d = self.model, self.data
        for i in range(n):
            d.ctrl[:3] = q_ref[i]
            d.ctrl[3:] = qd_ref[i]
            mujoco.mj_step(m, d)
            now = self.time + (i + 1) * dt
            piece, depth = self._touch()
            if piece >= 0:
                if open_ev is None:
                    open_ev = [now, now, piece, depth]
                open_ev[1], open_ev[3] = now, max(open_ev[3], depth)
            elif open_ev is not None and now - open_ev[1] > CONTACT_GAP:
                events.append(ContactEvent(open_ev[0], open_ev[1], int(open_ev[2]), open_ev[3]))
                open_ev = None
            if (i + 1) % obj_every == 0:
                w, z = d.qpos[self._puck + 3], d.qpos[self._puck + 6]
                rec_o.append((now, d.qpos[self._puck], d.qpos[self._puck + 1], 2.0 * np.arctan2(z, w)))
            if (i + 1) % tool_every == 0:
                rec_t.append(np.concatenate([[now], self._tool_pose(), d.qpos[self._q], q_ref[i], [piece >= 0]]))
        if open_ev is not None:
            events.append(ContactEvent(open_ev[0], open_ev[1], int(open_ev[2]), open_ev[3]))
        self.time += n * dt
        o = np.array(rec_o).reshape(-1, 4)
        k = np.array(rec_t).reshape(-1, 11)
        return Execution(o[:, 0], o[:, 1:3], o[:, 3], k[:, 0], k[:, 1:4], k[:, 4:7], k[:, 7:10], k[:, 10] > 0.5,
                         tuple(events))

    def execute_tool_path(self, t: ArrayLike, tool_xy: ArrayLike, rates: Rates | None = None) -> Execution:
        """Track a tool centre point path ``tool_xy`` (T, 2) [m] over ``t`` (T,) [s] through the
        Omni's inverse kinematics (the heading follows q1)."""
        tt = check_time(t, "t", min_len=2)
        xy = check_array(tool_xy, "tool_xy", shape=(tt.size, 2))
        jp = joint_path(self.platform, xy)
        bad = np.flatnonzero(~(jp.violation == 0.0))
        if bad.size:
            i = int(bad[0])
            raise InputError(f"tool_xy[{i}]", "a point the Omni reaches within its joint limits",
                             f"{xy[i].tolist()} (limit violation {jp.violation[i]:.3g} rad)")
        return self.execute(tt, jp.q, rates=rates)
