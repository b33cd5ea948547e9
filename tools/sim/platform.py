"""The simulated Omni platform: run joint or tool paths with PD tracking and record what happens.

:class:`SimPlatform` is stateful, so an operator can execute in chunks, look at the puck
(:meth:`SimPlatform.observe`) and correct; executing a path in chunks gives the recording of
executing it at once (up to the rounding of step times, when the chunks share the velocity
reference at the cut: pass ``qd``, as finite differences differ there). Recordings
(:class:`tooltransfer.tools.sim.execution.Execution`) come at requested rates: the object centre as a camera
sees it, the tool pose and joints as the encoders give them, plus the tool-object contact events.

Example::

    sim = SimPlatform(load_tool("finger"))
    sim.reset(object_xy=[0.0, 0.15], tool_xy=[0.0, 0.12])
    ex = sim.execute_tool_path(t, tool_xy)          # t (T,) [s], tool_xy (T, 2) [m]
    obj, tool_pose = sim.observe()
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, Obstacle
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim.config import SimConfig
from tooltransfer.tools.sim.execution import Execution, Rates
from tooltransfer.tools.sim.mjcf import PUCK, tool_piece_names
from tooltransfer.tools.sim.model import STATE_SPEC, SimModel
from tooltransfer.tools.sim.recorder import record
from tooltransfer.tools.sim.reference import joint_reference, tool_path_joints
from tooltransfer.validation import check_array

#: Largest jump [rad] allowed between the arm's joints and the first reference sample of an
#: execution (a larger one would be a step input to the PD loop, not a path to track).
MAX_JUMP = 0.05
#: Largest overlap [m] of the puck with the tool or an obstacle accepted at :meth:`SimPlatform.reset`.
RESET_OVERLAP = 1e-4


def check_obstacles(obstacles: object) -> tuple[Obstacle, ...]:
    """The obstacles as a tuple, or :class:`InputError` when it is not a sequence of them."""
    if isinstance(obstacles, SimConfig):
        raise InputError("obstacles", "a sequence of discs and polygons (pass the SimConfig as config=)",
                         "a SimConfig")
    if not isinstance(obstacles, Sequence):
        raise InputError("obstacles", "a sequence of discs and polygons", type(obstacles).__name__)
    for i, o in enumerate(obstacles):
        if not isinstance(o, Disc | shapely.Polygon) or (isinstance(o, shapely.Polygon) and not o.is_valid):
            raise InputError(f"obstacles[{i}]", "a tooltransfer.tools.objects.Disc or a valid shapely Polygon",
                             repr(o)[:60])
    return tuple(obstacles)


class SimPlatform:
    """The Omni carrying ``tool`` with the puck (and ``obstacles``) in MuJoCo.

    Args:
        tool: the tool.
        platform: the Omni (default: :class:`OmniPlatform` with the tool's ``a_t``).
        obstacles: discs (:class:`tooltransfer.tools.objects.Disc`) and polygons on the table (world frame [m]).
        config: physical settings (default :class:`SimConfig`).

    Attributes:
        time: the platform's clock [s] (0 at :meth:`reset`).
        sim: the compiled model and its addresses; model, data: MuJoCo's model and state.
    """

    def __init__(
        self, tool: Tool, platform: OmniPlatform | None = None, obstacles: Sequence[Obstacle] = (),
        config: SimConfig | None = None,
    ) -> None:
        if not isinstance(tool, Tool):
            raise InputError("tool", "a Tool (see tools.load_tool)", type(tool).__name__)
        if platform is not None and not isinstance(platform, OmniPlatform):
            raise InputError("platform", "an OmniPlatform or None", type(platform).__name__)
        if config is not None and not isinstance(config, SimConfig):
            raise InputError("config", "a SimConfig or None", type(config).__name__)
        self.tool = tool
        self.platform = platform or OmniPlatform(a_t=tool.a_t)
        self.sim = SimModel.build(tool, self.platform, check_obstacles(obstacles), config)
        self.config = self.sim.config
        self.model = self.sim.model
        self.data = mujoco.MjData(self.model)
        self._step = 0
        self._pieces = {self.model.geom(n).id for n in tool_piece_names(tool)}
        self._puck = self.model.geom(PUCK).id
        self.reset(np.array([0.0, 0.3]), q0=np.zeros(3))

    @property
    def time(self) -> float:
        """The platform's clock [s]: physics steps since :meth:`reset` times the step."""
        return self._step * self.sim.timestep

    @property
    def xml(self) -> str:
        """The MJCF text of the model."""
        return self.sim.xml

    # ------------------------------------------------------------------ state
    def reset(self, object_xy: ArrayLike, q0: ArrayLike | None = None, tool_xy: ArrayLike | None = None) -> None:
        """Put the puck at rest at ``object_xy`` (2,) [m] and the arm at rest at ``q0`` (3,) [rad], or
        where its tool centre point is at ``tool_xy`` (2,) [m]; the clock restarts at 0.

        Raises:
            InputError: no start given, the start is outside the joint limits or unreachable, or the
                puck overlaps the tool or an obstacle.
        """
        xy = check_array(object_xy, "object_xy", shape=(2,))
        if q0 is None:
            if tool_xy is None:
                raise InputError("q0", "joint angles, or a tool_xy to start from")
            txy = check_array(tool_xy, "tool_xy", shape=(2,))
            q = tool_path_joints(self.platform, np.vstack([txy, txy]), np.array([0.0, 1.0]))[0]
        else:
            q = check_array(q0, "q0", shape=(3,))
            bad = self.platform.limits.violated(q, 1e-6)
            if bad:
                raise InputError("q0", "joints within the platform's limits", f"{q.tolist()} (joint(s) "
                                 f"{[j + 1 for j in bad]} outside)")
        m, d = self.model, self.data
        self.sim.set_configuration(d, xy, q)
        mujoco.mj_fwdPosition(m, d)
        for c in d.contact[: d.ncon]:
            g1, g2 = int(c.geom[0]), int(c.geom[1])
            if self._puck in (g1, g2) and -c.dist > RESET_OVERLAP:
                other = m.geom(g2 if g1 == self._puck else g1).name
                if other != "table":
                    raise InputError("object_xy", f"a puck position clear of {other}",
                                     f"{xy.tolist()} overlapping by {1e3 * -c.dist:.2f} mm")
        self.sim.set_configuration(d, xy, q)
        self._step = 0

    def observe(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The current object centre (2,) [m] and tool pose (3,) (x, y [m], yaw [rad]), world frame."""
        return self.sim.current_pose(self.data)

    @property
    def joints(self) -> NDArray[np.float64]:
        """The arm's current joints (3,) [rad]."""
        return self.data.qpos[[self.model.joint(n).qposadr[0] for n in ("q1", "q2", "q3")]].copy()

    # ------------------------------------------------------------------ running
    def execute(self, t: ArrayLike, q: ArrayLike, qd: ArrayLike | None = None, rates: Rates | None = None) -> Execution:
        """Track a joint path with the PD actuators, continuing from the current state.

        Args:
            t: shape (T,), increasing times [s] (relative: only differences matter; the path runs
                from the current clock for ``t[-1] - t[0]``, rounded to physics steps).
            q: shape (T, 3), joints [rad] within the limits, linearly interpolated to the steps; ``q[0]``
                within :data:`MAX_JUMP` of the arm's current joints.
            qd: shape (T, 3), joint velocities [rad/s]; default: finite differences of ``q``.
            rates: recording rates (default :class:`Rates`).

        Returns:
            The recording of the steps from the current clock to the end (excluded; the state at the
            end is what :meth:`observe` gives).
        """
        r = rates or Rates()
        if not isinstance(r, Rates):
            raise InputError("rates", "a Rates", type(r).__name__)
        dt = self.sim.timestep
        ref = joint_reference(t, q, qd, dt, self.platform)
        jump = np.abs(ref.q[0] - self.joints)
        if jump.max() > MAX_JUMP:
            raise InputError("q[0]", f"a start within {MAX_JUMP} rad of the arm's joints {self.joints.tolist()}",
                             f"{ref.q[0].tolist()}")
        d = self.data
        start = self.sim.state(d)[None]
        final, sens = self.sim.run(d, start, d.qacc_warmstart.copy()[None], self.sim.controls(ref.q, ref.qd)[None])
        # the rollout stepped ``d`` itself (warm start included); set the final state explicitly anyway
        mujoco.mj_setState(self.model, d, final[0], STATE_SPEC)
        mujoco.mj_kinematics(self.model, d)
        ex = record(self.tool, self.sim.sensor_rows(sens[0]), self._step, dt, ref.q, r)
        self._step += len(ref.q)
        return ex

    def execute_tool_path(self, t: ArrayLike, tool_xy: ArrayLike, rates: Rates | None = None) -> Execution:
        """Track a tool centre point path ``tool_xy`` (T, 2) [m] (world, table plane) over times
        ``t`` (T,) [s] through the Omni's inverse kinematics; the tool's heading is not free, it
        follows q1 (so it turns as the tool sweeps sideways). See :meth:`execute`.

        Raises:
            InputError: naming the first sample the Omni cannot reach within its joint limits.
        """
        return self.execute(t, tool_path_joints(self.platform, tool_xy, t), rates=rates)
