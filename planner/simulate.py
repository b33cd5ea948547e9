"""Executing a plan on the simulated platform, open loop as the paper did: PD tracking of the
planned joints; reports the object's final error and the tracking error."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.plan import Plan
from problems.task import Task, task_from_dict, task_obstacles, task_platform, task_tool
from tools.sim import Execution, SimPlatform
from tools.sim.config import SimConfig


def task_sim_config(task: Task, **overrides: float) -> SimConfig:
    """The simulated platform's settings for ``task``'s object (radius, mass, table friction), with
    ``overrides`` of any :class:`SimConfig` field (e.g. ``tool_friction=0.5`` for a mismatched plant)."""
    o = task.object
    return SimConfig(**{"puck_radius": o.radius, "puck_mass": o.mass, "table_friction": o.friction, **overrides})


@dataclass(frozen=True)
class SimulationReport:
    """Outcome of executing a plan: final object error [m] against the goal, largest tool-path
    deviation from the plan [m], joint tracking error [rad], wall time [s] and the recording."""

    final_error: float
    tool_deviation: float
    tracking_error: float
    wall_time: float
    execution: Execution


def simulate_plan(plan: Plan, config: SimConfig | None = None) -> SimulationReport:
    """Execute a solved plan in MuJoCo (open loop) with the physical settings ``config`` (default:
    the task's object, :func:`task_sim_config`)."""
    import time

    task = task_from_dict(plan.task, "plan.task")
    tool = task_tool(task)
    sim = SimPlatform(tool, task_platform(task, tool), task_obstacles(task), config or task_sim_config(task))
    start = time.perf_counter()
    sim.reset(np.array(task.start), q0=plan.joints[0])
    ex = sim.execute(plan.t, plan.joints)
    wall = time.perf_counter() - start
    planned = np.column_stack([np.interp(ex.t_tool, plan.t, plan.tool_pose[:, j]) for j in range(2)])
    return SimulationReport(
        final_error=float(np.linalg.norm(ex.object_xy[-1] - np.array(task.target))),
        tool_deviation=float(np.linalg.norm(ex.tool_pose[:, :2] - planned, axis=1).max()),
        tracking_error=ex.tracking_error, wall_time=wall, execution=ex,
    )
