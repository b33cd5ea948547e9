"""Many executions at once: independent jobs, each from a fresh reset, stepped by
:func:`mujoco.rollout.rollout` on its thread pool (the physics runs without the GIL).

The PD tracking is in the actuators, so a job's controls are known before it runs (its joint
reference), which is what a rollout needs. Jobs of different lengths are padded with their last
control to the longest and cut back afterwards (the physics is causal, so the padding changes
nothing before it). Each job's recording is bit-identical to :meth:`SimPlatform.execute` after
:meth:`SimPlatform.reset` (tested), whatever the number of threads.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Obstacle
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim.config import SimConfig
from tooltransfer.tools.sim.execution import Execution, Rates
from tooltransfer.tools.sim.model import SimModel
from tooltransfer.tools.sim.platform import check_obstacles
from tooltransfer.tools.sim.recorder import record
from tooltransfer.tools.sim.reference import joint_reference, tool_path_joints
from tooltransfer.validation import check_array


@dataclass(frozen=True)
class Job:
    """One execution from rest: the puck's start ``object_xy`` (2,) [m], the joint path ``q`` (T, 3)
    [rad] over times ``t`` (T,) [s] (the arm starts at rest at ``q[0]``), optionally its joint
    velocities ``qd`` (T, 3) [rad/s]."""

    object_xy: NDArray[np.float64]
    t: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64] | None = None

    @staticmethod
    def from_tool_path(platform: OmniPlatform, object_xy: ArrayLike, t: ArrayLike, tool_xy: ArrayLike) -> Job:
        """The job tracking the tool centre point path ``tool_xy`` (T, 2) [m] over ``t`` (T,) [s]
        (through the Omni's inverse kinematics, as :meth:`SimPlatform.execute_tool_path`)."""
        q = tool_path_joints(platform, tool_xy, t)
        return Job(check_array(object_xy, "object_xy", shape=(2,)), np.asarray(t, dtype=np.float64), q)


def execute_many(
    tool: Tool, jobs: Sequence[Job], *, platform: OmniPlatform | None = None, obstacles: Sequence[Obstacle] = (),
    config: SimConfig | None = None, rates: Rates | None = None, threads: int = 1,
) -> list[Execution]:
    """Run ``jobs`` on one platform model, each from a fresh reset, on ``threads`` threads.

    Returns:
        The recordings, in the jobs' order.

    Raises:
        InputError: naming the job (``jobs[i].q`` ...) that is invalid.
    """
    if threads < 1:
        raise InputError("threads", "at least 1", threads)
    plat = platform or OmniPlatform(a_t=tool.a_t)
    sm = SimModel.build(tool, plat, check_obstacles(obstacles), config)
    r = rates or Rates()
    if not jobs:
        return []
    scratch = mujoco.MjData(sm.model)
    refs, states = [], []
    for i, job in enumerate(jobs):
        try:
            ref = joint_reference(job.t, job.q, job.qd, sm.timestep, plat)
            xy = check_array(job.object_xy, "object_xy", shape=(2,))
        except InputError as exc:
            raise InputError(f"jobs[{i}].{exc.field}", exc.expected, exc.got) from exc
        sm.set_configuration(scratch, xy, ref.q[0])
        states.append(sm.state(scratch))
        refs.append(ref)
    n = max(len(ref.q) for ref in refs)
    controls = np.empty((len(jobs), n, 6))
    for b, ref in enumerate(refs):
        c = sm.controls(ref.q, ref.qd)
        controls[b, : len(c)] = c
        controls[b, len(c) :] = c[-1]
    datas = [mujoco.MjData(sm.model) for _ in range(min(threads, len(jobs)))]
    _, sens = sm.run(datas if len(datas) > 1 else datas[0], np.array(states),
                     np.zeros((len(jobs), sm.model.nv)), controls)
    return [record(tool, sm.sensor_rows(sens[b, : len(ref.q)]), 0, sm.timestep, ref.q, r)
            for b, ref in enumerate(refs)]
