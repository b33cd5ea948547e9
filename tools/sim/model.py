"""The compiled MuJoCo model of the platform and where its quantities live (state, controls, sensors).

:class:`SimModel` is shared by the stateful :class:`tooltransfer.tools.sim.platform.SimPlatform` and the batch
runner :mod:`tooltransfer.tools.sim.batch`: it builds a full physics state from a puck position and joint
angles, turns joint references into the actuators' controls, and reads recorded sensor rows back
as named arrays.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import mujoco
import mujoco.rollout
import numpy as np
from numpy.typing import NDArray

from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Obstacle
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim.config import SimConfig
from tooltransfer.tools.sim.mjcf import (
    ARM_JOINTS,
    LEVEL_JOINTS,
    PUCK,
    TCP_BODY,
    TOOL_BODY,
    build_mjcf,
    tool_piece_names,
)

#: State components a simulation is saved and restored with (time, qpos, qvel, activations...).
STATE_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS
#: Oldest MuJoCo with what the model needs (contact sensors; the solver's warm start saved by
#: ``mj_step``, so rollouts chain); the contact settings (:mod:`tooltransfer.tools.sim.mjcf`) are
#: chosen for MuJoCo 4.0.
MIN_MUJOCO = (3, 3, 6)
if tuple(int(p) for p in re.findall(r"\d+", mujoco.__version__)[:3]) < MIN_MUJOCO:  # pragma: no cover
    raise ImportError(f"tooltransfer.tools.sim needs mujoco >= {'.'.join(map(str, MIN_MUJOCO))}, "
                      f"found {mujoco.__version__}")


class SensorRows(NamedTuple):
    """Sensor data of ``n`` physics steps as named arrays (world frame, SI units).

    Attributes:
        joints (n, 3) [rad]; tcp (n, 3) tool centre point [m]; tool_x (n, 3), tool_z (n, 3) unit
        axes of the planar tool frame; puck_pos (n, 3) [m]; puck_quat (n, 4) (w, x, y, z);
        touch_found (n, P) number of contacts of each tool piece with the puck; touch_dist (n, P)
        signed distance of its deepest one [m] (negative: penetration; 0 without contact);
        touch_pos (n, P, 3) the position of that contact [m].
    """

    joints: NDArray[np.float64]
    tcp: NDArray[np.float64]
    tool_x: NDArray[np.float64]
    tool_z: NDArray[np.float64]
    puck_pos: NDArray[np.float64]
    puck_quat: NDArray[np.float64]
    touch_found: NDArray[np.float64]
    touch_dist: NDArray[np.float64]
    touch_pos: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SimModel:
    """The platform's compiled model and its addresses.

    Attributes:
        tool, platform, obstacles, config: what it was built from.
        xml: the MJCF text; model: the compiled ``mujoco.MjModel``.
    """

    tool: Tool
    platform: OmniPlatform
    obstacles: tuple[Obstacle, ...]
    config: SimConfig
    xml: str
    model: mujoco.MjModel

    @staticmethod
    def build(
        tool: Tool, platform: OmniPlatform, obstacles: Sequence[Obstacle] = (), config: SimConfig | None = None
    ) -> SimModel:
        """Write the MJCF (:func:`tooltransfer.tools.sim.mjcf.build_mjcf`) and compile it."""
        cfg = config or SimConfig()
        xml = build_mjcf(tool, platform, obstacles, cfg)
        return SimModel(tool, platform, tuple(obstacles), cfg, xml, mujoco.MjModel.from_xml_string(xml))

    @property
    def timestep(self) -> float:
        """Physics step [s]."""
        return float(self.model.opt.timestep)

    @property
    def n_pieces(self) -> int:
        """Number of the tool's convex pieces (prisms)."""
        return len(tool_piece_names(self.tool))

    def _qadr(self, names: Sequence[str]) -> NDArray[np.intp]:
        return np.array([self.model.joint(n).qposadr[0] for n in names])

    def set_configuration(self, data: mujoco.MjData, object_xy: NDArray[np.float64], q: NDArray[np.float64]) -> None:
        """Reset ``data`` to rest with the puck flat at ``object_xy`` (2,) [m], the arm at ``q`` (3,)
        [rad] (the tool level) and the actuators holding it there; runs the kinematics."""
        m = self.model
        mujoco.mj_resetData(m, data)
        p = m.joint(PUCK).qposadr[0]
        data.qpos[p : p + 7] = [object_xy[0], object_xy[1], self.config.puck_height / 2, 1.0, 0.0, 0.0, 0.0]
        data.qpos[self._qadr(ARM_JOINTS)] = q
        data.qpos[self._qadr(LEVEL_JOINTS)] = -q[1:]
        data.ctrl[:3], data.ctrl[3:] = q, 0.0
        mujoco.mj_kinematics(m, data)

    def controls(self, q_ref: NDArray[np.float64], qd_ref: NDArray[np.float64]) -> NDArray[np.float64]:
        """Actuator controls (n, 6) for joint references ``q_ref`` (n, 3) [rad], ``qd_ref`` (n, 3) [rad/s]:
        the position actuators take ``q_ref``, the velocity actuators ``qd_ref``."""
        return np.ascontiguousarray(np.hstack([q_ref, qd_ref]))

    def sensor_rows(self, sensordata: NDArray[np.float64]) -> SensorRows:
        """Split sensor data (n, nsensordata) into named arrays."""
        m = self.model

        def col(name: str) -> NDArray[np.float64]:
            s = m.sensor(name)
            return sensordata[:, s.adr[0] : s.adr[0] + s.dim[0]]

        pieces = tool_piece_names(self.tool)
        touch = np.stack([col(f"touch_{n}") for n in pieces], axis=1)  # (n, P, 5): found, dist, pos
        return SensorRows(
            joints=np.hstack([col(n) for n in ARM_JOINTS]),
            tcp=col("tcp"),
            tool_x=col("tool_x"),
            tool_z=col("tool_z"),
            puck_pos=col("puck_pos"),
            puck_quat=col("puck_quat"),
            touch_found=touch[:, :, 0],
            touch_dist=touch[:, :, 1],
            touch_pos=touch[:, :, 2:5],
        )

    def current_pose(self, data: mujoco.MjData) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Object centre (2,) [m] and tool pose (3,) (x, y [m], heading [rad]) in ``data``, whose
        kinematics must be current."""
        p = self.model.joint(PUCK).qposadr[0]
        tcp = data.body(TCP_BODY).xpos
        xm = data.body(TOOL_BODY).xmat.reshape(3, 3)
        return data.qpos[p : p + 2].copy(), np.array([tcp[0], tcp[1], np.arctan2(xm[1, 0], xm[0, 0])])

    def state(self, data: mujoco.MjData) -> NDArray[np.float64]:
        """The full physics state of ``data`` (nstate,) (:data:`STATE_SPEC`)."""
        out = np.empty(mujoco.mj_stateSize(self.model, STATE_SPEC))
        mujoco.mj_getState(self.model, data, out, STATE_SPEC)
        return out

    def run(
        self, data: mujoco.MjData | Sequence[mujoco.MjData], states: NDArray[np.float64],
        warmstarts: NDArray[np.float64], controls: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Step simulations open loop with :func:`mujoco.rollout.rollout` (its thread pool when
        ``data`` is a sequence of several, one per thread).

        Args:
            data: the MjData to step with (one, or one per thread).
            states: shape (B, nstate), the initial states; warmstarts: shape (B, nv), the solver's
                warm start (``qacc_warmstart``) of each.
            controls: shape (B, n, 6), the controls of every step.

        Returns:
            The final states (B, nstate) and the sensor data (B, n, nsensordata) of each step
            (computed at the start of the step, as ``mj_step`` does). Bit-identical to ``mj_step``
            in a loop, whatever the number of threads.
        """
        state, sens = mujoco.rollout.rollout(
            self.model, data, states, controls, initial_warmstart=warmstarts,
        )
        return state[:, -1, :], sens
