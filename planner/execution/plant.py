"""What the closed loop drives: a plant behind a small protocol, and the plants of this project.

:class:`Plant` is all :func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop` needs of a robot:

* ``observe_object() -> (2,)``: the object's centre [m] in the world frame, as the camera sees it
  (noisy: the loop averages several calls while the object rests);
* ``tool_pose() -> (3,)``: the tool pose ``x, y`` [m], ``yaw`` [rad] from the encoders;
* ``move_tool(t, tool_pose)``: track the tool path ``tool_pose`` (K, 3) at times ``t`` (K,) [s]
  from 0, starting at the current pose, and return when it is done. On the Omni the heading follows
  the waist, so a plant may take the yaw as a check rather than a command.

Plants here: :class:`SimPlant`, the MuJoCo platform (PD tracking through the Omni's inverse
kinematics, the camera's noise; :func:`sim_plant` builds it for a setting); :class:`ModelPlant`, the
quasi-static push model of :mod:`tooltransfer.tools.pushing` (a plant with other mechanics than the
planner assumes, for tests and for studies of mismatch). Both also answer ``true_object()`` (not
part of the protocol), so reports give the true error rather than the camera's.

Wrapping a real device: implement the three methods over its drivers, e.g. for a Phantom Omni with
a camera, ``observe_object`` returns the latest camera estimate of the puck's centre transformed
into the world frame of docs/design.md section 2 (origin under joint 1, metres), ``tool_pose`` the forward
kinematics of the encoder angles (:func:`tooltransfer.tools.omni.ik.table_pose`), and ``move_tool`` turns the
path into joints with :func:`tooltransfer.tools.sim.reference.tool_path_joints` (which checks the joint limits)
and streams them to the device's PD loop at its rate, blocking until the last sample. An exception
it raises ends the closed loop with the method and the exception in the reason (a lost camera frame
or tool pose reading is taken again first); a ``stop()`` method, when the driver has one, is what the
loop calls to stop the tool on ``KeyboardInterrupt``. The closed loop sends no command outside its
safety envelope (:mod:`tooltransfer.planner.execution.guarded_plant`), and
:mod:`tooltransfer.planner.execution.fault_plants` injects a device's faults into any plant to test
a driver and the loop against them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pushing.forward import simulate
from tooltransfer.tools.pushing.mechanics import PushMechanics
from tooltransfer.validation import check_array

if TYPE_CHECKING:
    from tooltransfer.planner.planning.setting import Setting
    from tooltransfer.tools.sim import SimConfig


@runtime_checkable
class Plant(Protocol):
    """A robot the closed loop can drive (module docstring)."""

    def observe_object(self) -> NDArray[np.float64]:
        """The object's centre (2,) [m], world frame, possibly noisy."""
        ...

    def tool_pose(self) -> NDArray[np.float64]:
        """The tool pose (3,): ``x, y`` [m], ``yaw`` [rad]."""
        ...

    def move_tool(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        """Track ``tool_pose`` (K, 3) at times ``t`` (K,) [s] from 0, starting at the current pose."""
        ...


#: Time [s] the simulated platform runs with the arm held still after the puck is displaced.
SETTLE = 0.2


def _check_path(t: ArrayLike, tool_pose: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    tt = check_array(t, "t", ndim=1)
    pose = check_array(tool_pose, "tool_pose", shape=(tt.size, 3))
    if tt.size < 2 or tt[0] != 0.0 or np.any(np.diff(tt) <= 0):
        raise InputError("t", "at least 2 increasing times [s] from 0", f"{tt.size} samples")
    return tt, pose


class SimPlant:
    """The MuJoCo platform of :mod:`tooltransfer.tools.sim` as a :class:`Plant`.

    Args:
        sim: the simulated platform (already reset where the run starts).
        camera_noise: standard deviation [m] per axis of one camera frame (the dataset's 1.5 mm).
        seed: seed of the camera noise (``numpy.random.default_rng``).
    """

    def __init__(self, sim: object, camera_noise: float = 0.0015, seed: int = 0) -> None:
        from tooltransfer.tools.sim import SimPlatform

        if not isinstance(sim, SimPlatform):
            raise InputError("sim", "a tooltransfer.tools.sim.SimPlatform", type(sim).__name__)
        if not np.isfinite(camera_noise) or camera_noise < 0:
            raise InputError("camera_noise", "a standard deviation >= 0 [m]", camera_noise)
        self.sim, self.noise, self.rng = sim, float(camera_noise), np.random.default_rng(seed)
        self.parts: list = []

    def observe_object(self) -> NDArray[np.float64]:
        return self.true_object() + self.rng.normal(0.0, self.noise, 2)

    def true_object(self) -> NDArray[np.float64]:
        """The object's true centre (2,) [m] (for reports)."""
        return self.sim.observe()[0]

    def tool_pose(self) -> NDArray[np.float64]:
        return self.sim.observe()[1]

    def move_tool(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        tt, pose = _check_path(t, tool_pose)
        self.parts.append(self.sim.execute_tool_path(tt, pose[:, :2]))

    def displace_object(self, displacement: ArrayLike) -> None:
        """Move the puck by ``displacement`` (2,) [m] and bring it to rest (something else than the
        tool knocked it: :class:`tooltransfer.planner.execution.fault_plants.Bump`)."""
        import mujoco

        from tooltransfer.tools.sim.mjcf import PUCK

        d = check_array(displacement, "displacement", shape=(2,))
        m, data = self.sim.model, self.sim.data
        j = m.joint(PUCK)
        data.qpos[j.qposadr[0]: j.qposadr[0] + 2] += d
        data.qvel[j.dofadr[0]: j.dofadr[0] + 6] = 0.0
        mujoco.mj_forward(m, data)
        here = self.tool_pose()[:2]  # the arm holds still while the contacts settle
        self.parts.append(self.sim.execute_tool_path(np.array([0.0, SETTLE]), np.vstack([here, here])))

    @property
    def execution(self) -> object:
        """Everything recorded so far (:class:`tooltransfer.tools.sim.Execution`; None before the first move)."""
        from tooltransfer.tools.sim import Execution

        return Execution.concat(self.parts) if self.parts else None


def sim_plant(setting: Setting, config: SimConfig, start: ArrayLike, q0: ArrayLike, camera_noise: float = 0.0015,
              seed: int = 0) -> SimPlant:
    """The MuJoCo platform of ``setting`` (its tool, Omni and obstacles; ``config`` the simulation's
    settings) with the object at ``start`` (2,) [m] and the arm at joints ``q0`` (3,) [rad], as a
    :class:`SimPlant` with a camera of ``camera_noise`` [m] per frame (seed ``seed``)."""
    from tooltransfer.tools.sim import SimPlatform

    sim = SimPlatform(setting.tool, setting.platform, list(setting.obstacles), config)
    sim.reset(np.array(start), q0=q0)
    return SimPlant(sim, camera_noise, seed)


class ModelPlant:
    """The quasi-static push model as a :class:`Plant`: the tool follows the commanded poses exactly,
    the object moves as :func:`tooltransfer.tools.pushing.forward.simulate` says with ``mechanics`` (which may
    differ from the planner's: a mismatched plant).

    Args:
        tool: the tool; radius: the object's radius [m]; mechanics: the plant's push parameters.
        object_xy: (2,) the object's start [m]; tool_pose: (3,) the tool's start.
        platform: when given, commanded paths are checked against the Omni's reach and joint limits
            (as a real device would refuse them: :class:`~tooltransfer.errors.InputError`).
        camera_noise, seed: as :class:`SimPlant`'s.
    """

    def __init__(self, tool: Tool, radius: float, mechanics: PushMechanics, object_xy: ArrayLike,
                 tool_pose: ArrayLike, *, platform: OmniPlatform | None = None, camera_noise: float = 0.0,
                 seed: int = 0) -> None:
        self.tool, self.radius, self.mechanics, self.platform = tool, float(radius), mechanics, platform
        self.obj = check_array(object_xy, "object_xy", shape=(2,)).copy()
        self.pose = check_array(tool_pose, "tool_pose", shape=(3,)).copy()
        self.noise, self.rng = float(camera_noise), np.random.default_rng(seed)
        self.history: list[NDArray[np.float64]] = [self.obj.copy()]

    def observe_object(self) -> NDArray[np.float64]:
        return self.obj + self.rng.normal(0.0, self.noise, 2)

    def true_object(self) -> NDArray[np.float64]:
        """The object's true centre (2,) [m]."""
        return self.obj.copy()

    def tool_pose(self) -> NDArray[np.float64]:
        return self.pose.copy()

    def move_tool(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        _, pose = _check_path(t, tool_pose)
        if self.platform is not None:
            bad = np.flatnonzero(joint_path(self.platform, pose[:, :2]).refused)
            if bad.size:
                raise InputError("tool_pose", "a path the Omni reaches within its joint limits",
                                 f"sample {int(bad[0])} at {np.round(pose[bad[0], :2], 4).tolist()} m")
        path = np.vstack([self.pose, pose])
        trace = simulate(self.tool, path, self.obj, self.radius, self.mechanics)
        self.obj, self.pose = trace.final.copy(), pose[-1].copy()
        self.history.append(self.obj.copy())

    def displace_object(self, displacement: ArrayLike) -> None:
        """Move the object by ``displacement`` (2,) [m] (something else than the tool knocked it:
        :class:`tooltransfer.planner.execution.fault_plants.Bump`)."""
        self.obj = self.obj + check_array(displacement, "displacement", shape=(2,))
        self.history.append(self.obj.copy())
