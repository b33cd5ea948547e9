"""Executing a plan on the simulated platform, open loop as the paper did: PD tracking of the
planned joints; reports the object's final error and the tracking error.

Before a plan file is run (``tooltransfer simulate``), :func:`check_plan` checks it against itself
and its task: a hand-edited plan whose tool sweeps through the puck, that moves faster than the
tool's limits or whose joints do not give its tool poses is refused naming the file and the field
(``--force`` runs it anyway, with a warning).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.planning.plan import Plan, PlanFileError, joint_rates
from tooltransfer.planner.planning.setting import Setting, setting_from_task, task_mechanics
from tooltransfer.problems.task import Task, task_from_dict
from tooltransfer.tools.pose import wrap_angle
from tooltransfer.tools.pushing.mechanics import PushMechanics

if TYPE_CHECKING:  # the simulation's types (imported where it runs: checking or exporting a plan needs neither)
    from tooltransfer.tools.omni.platform import OmniPlatform
    from tooltransfer.tools.sim.config import SimConfig
    from tooltransfer.tools.sim.execution import Execution


def task_sim_config(task: Task, **overrides: float) -> SimConfig:
    """The simulated platform's settings for ``task``'s object (radius, mass, table friction), with
    ``overrides`` of any :class:`SimConfig` field (e.g. ``tool_friction=0.5`` for a mismatched plant)."""
    from tooltransfer.tools.sim.config import SimConfig

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
    the task's object, :func:`task_sim_config`).

    Raises:
        InputError: a plan longer than :data:`MAX_PLAN_DURATION` (a bound on the simulation's time
            and memory; :func:`check_plan` checks the rest of a plan file).
    """
    import time

    if plan.t.size < 2 or not plan.t[-1] - plan.t[0] <= MAX_PLAN_DURATION:
        raise InputError("plan.t", f"a plan of 2 samples or more lasting at most {MAX_PLAN_DURATION:g} s (the "
                         "simulation's bound, --force or not)",
                         f"{plan.t.size} samples, {plan.t[-1] - plan.t[0]:.6g} s" if plan.t.size else "no samples")
    task = task_from_dict(plan.task, "plan.task")
    setting = setting_from_task(task, mechanics=task_mechanics(task), margin=task.safety_margin)  # MuJoCo's physics
    from tooltransfer.tools.sim.platform import SimPlatform  # mujoco: the optional sim extra

    sim = SimPlatform(setting.tool, setting.platform, list(setting.obstacles), config or task_sim_config(task))
    start = time.perf_counter()
    sim.reset(np.array(task.start), q0=plan.joints[0])
    ex = sim.execute(plan.t, plan.joints, plan.joint_velocities)  # the plan's velocities fed forward
    wall = time.perf_counter() - start
    planned = np.column_stack([np.interp(ex.t_tool, plan.t, plan.tool_pose[:, j]) for j in range(2)])
    return SimulationReport(
        final_error=float(np.linalg.norm(ex.object_xy[-1] - np.array(task.target))),
        tool_deviation=float(np.linalg.norm(ex.tool_pose[:, :2] - planned, axis=1).max()),
        tracking_error=ex.tracking_error, wall_time=wall, execution=ex,
    )


#: Longest plan :func:`check_plan` lets run [s] (the planner's plans last tens of seconds; the
#: simulation runs faster than real time, ``benchmarks/bench_sim.py``).
MAX_PLAN_DURATION = 1800.0
#: Tolerances of :func:`check_plan`: the joints' forward kinematics against the tool poses [m, rad],
#: joint limits [rad], tool-object overlap [m], the start and the end of the object path [m], the
#: speed and acceleration limits (finite differences of the samples: the acceleration of a sampled
#: path with corners is noisy, so it is given a factor; a plan 1000 times too fast is far beyond
#: either), and the replay through the push model [m].
FK_TOL, YAW_TOL, LIMIT_TOL, OVERLAP_TOL, END_TOL = 1e-4, 1e-4, 1e-6, 2e-4, 1e-3
SPEED_FACTOR, ACCEL_FACTOR = 1.2, 50.0
REPLAY_TOL = 1e-3
#: Tolerance of the joints' velocities and accelerations against those the joints give
#: (:func:`tooltransfer.planner.planning.plan.joint_rates`): this share of their largest value, plus 1e-9 rad/s
#: (rad/s^2).
RATES_RTOL = 1e-6


class PlanLimitError(PlanFileError):
    """A plan beyond what the simulation runs at all (too long, too few samples): ``--force`` does not
    override it."""


def _fail(source: str, field: str, expected: str, got: object | None = None) -> NoReturn:
    """Raise the :class:`PlanFileError` of ``source``'s ``field``: what was ``expected`` and ``got``."""
    raise PlanFileError(source, field, expected, got)


def _check_joints(plan: Plan, source: str, platform: OmniPlatform) -> None:
    """The joints [rad] within the Omni's limits, and their forward kinematics the plan's tool poses
    (within ``FK_TOL`` [m] and ``YAW_TOL`` [rad])."""
    from tooltransfer.planner.learning.segmentation.geometry import table_poses

    t = plan.t
    lo, hi = np.asarray(platform.limits.lower), np.asarray(platform.limits.upper)
    out = (plan.joints < lo - LIMIT_TOL) | (plan.joints > hi + LIMIT_TOL)
    if out.any():
        k, j = (int(v) for v in np.argwhere(out)[0])
        _fail(source, f"samples.joints[{k}][{j}]",
              f"q{j + 1} within the Omni's joint limits [{lo[j]:.4g}, {hi[j]:.4g}] rad",
              f"{plan.joints[k, j]:.6g} rad at t = {t[k]:.3f} s")
    fk = table_poses(plan.joints, platform.a_t, platform.base_xy, platform.base_yaw, platform.table_height)
    pos = np.hypot(*(fk[:, :2] - plan.tool_pose[:, :2]).T)
    yaw = np.abs(wrap_angle(fk[:, 2] - plan.tool_pose[:, 2]))
    if pos.max() > FK_TOL or yaw.max() > YAW_TOL:
        k = int(np.argmax((pos > FK_TOL) | (yaw > YAW_TOL)))
        _fail(source, f"samples.tool_pose[{k}]", "the tool pose the joints give (forward kinematics of "
              f"samples.joints, within {1e3 * FK_TOL:g} mm and {YAW_TOL:g} rad)",
              f"{1e3 * pos[k]:.4g} mm and {yaw[k]:.3g} rad off at t = {t[k]:.3f} s")


def _check_clear(plan: Plan, source: str, setting: Setting, start: NDArray[np.float64]) -> None:
    """The tool clear of the object at the task's ``start`` [m], of the planned object path and of
    every obstacle (overlaps beyond ``OVERLAP_TOL`` [m] fail)."""
    from tooltransfer.planner.learning.segmentation.geometry import ToolGeometry, to_tool_frame
    from tooltransfer.planner.planning.tool_clearance import tool_obstacle_clearance

    t, tool = plan.t, setting.tool
    geo = ToolGeometry(tool, setting.radius)
    gap0 = float(geo.outline_gap(to_tool_frame(start, plan.tool_pose[:1]))[0][0])
    if gap0 < -OVERLAP_TOL:
        _fail(source, "samples.tool_pose[0]", "a start pose of the tool clear of the object at the task's start",
              f"the tool outline {1e3 * -gap0:.3g} mm into the object")
    gap = geo.outline_gap(to_tool_frame(plan.object_xy, plan.tool_pose))[0]
    if gap.min() < -OVERLAP_TOL:
        k = int(np.argmax(gap < -OVERLAP_TOL))
        _fail(source, f"samples.tool_pose[{k}]",
              "a tool path that never overlaps the planned object (samples.object_xy)",
              f"the tool outline {1e3 * -gap[k]:.3g} mm into the object at t = {t[k]:.3f} s ({plan.phase[k]})")
    near = tool_obstacle_clearance(tool, plan.tool_pose, list(setting.obstacles))
    if near.distance <= 0.0:
        k = near.sample
        _fail(source, f"samples.tool_pose[{k}]", f"a tool path clear of obstacles[{near.obstacle}]",
              f"the tool outline overlapping it at t = {t[k]:.3f} s ({plan.phase[k]})")


def _check_tool_rates(plan: Plan, source: str, task: Task) -> None:
    """Tool speeds [m/s] and accelerations [m/s^2] (finite differences) within the task's
    ``timing`` limits, up to ``SPEED_FACTOR`` and ``ACCEL_FACTOR`` times them."""
    t = plan.t
    v_max, a_max = task.timing.max_tool_speed, task.timing.max_tool_accel
    dt = np.diff(t)
    speed = np.hypot(*np.diff(plan.tool_pose[:, :2], axis=0).T) / dt
    if speed.max() > SPEED_FACTOR * v_max:
        k = int(np.argmax(speed))
        _fail(source, f"samples.t[{k + 1}]", f"tool speeds within timing.max_tool_speed = {v_max:g} m/s",
              f"{speed[k]:.4g} m/s ({speed[k] / v_max:.3g} times the limit) at t = {t[k]:.3f} s")
    if t.size >= 3:
        acc = np.hypot(*np.gradient(np.gradient(plan.tool_pose[:, :2], t, axis=0), t, axis=0).T)
        if acc.max() > ACCEL_FACTOR * a_max:
            k = int(np.argmax(acc))
            _fail(source, f"samples.t[{k}]", f"tool accelerations within timing.max_tool_accel = {a_max:g} m/s^2 "
                  f"(finite differences, up to {ACCEL_FACTOR:g} times it at the corners of the sampled path)",
                  f"{acc[k]:.4g} m/s^2 ({acc[k] / a_max:.3g} times the limit) at t = {t[k]:.3f} s")


def _plan_mechanics(plan: Plan, source: str, task: Task) -> PushMechanics:
    """The push model's parameters the plan records in its metrics, else the task's
    (:func:`tooltransfer.planner.planning.setting.task_mechanics`, without skills)."""
    mu, c = plan.metrics.get("mechanics_mu"), plan.metrics.get("mechanics_c")
    if mu is None or c is None:
        return task_mechanics(task)
    try:
        return PushMechanics(float(mu), float(c), "given")
    except InputError as exc:
        _fail(source, f"metrics.{exc.field.replace('mechanics.', 'mechanics_')}", exc.expected, exc.got)


def _check_replay(plan: Plan, source: str, task: Task, setting: Setting, start: NDArray[np.float64]) -> None:
    """The planned tool path, replayed through the push model from ``start`` [m] with the plan's
    mechanics (:func:`_plan_mechanics`), moves the object along the planned path."""
    from tooltransfer.tools.pushing.forward import object_path  # simulate's path, without naming the faces

    t = plan.t
    replay = object_path(setting.tool, plan.tool_pose, start, setting.radius, _plan_mechanics(plan, source, task))
    off = np.hypot(*(replay - plan.object_xy).T)
    tol = max(REPLAY_TOL, 10 * task.oe.self_consistency_tol)
    if off.max() > tol:
        k = int(np.argmax(off > tol))
        _fail(source, "samples.object_xy", f"the object path the planned tool path gives through the push model "
              f"(within {1e3 * tol:g} mm)", f"{1e3 * off.max():.3g} mm off, from t = {t[k]:.3f} s ({plan.phase[k]})")


def _check_joint_rates(plan: Plan, source: str) -> None:
    """The joints' velocities [rad/s] and accelerations [rad/s^2] those the joints give on the
    plan's times (:func:`tooltransfer.planner.planning.plan.joint_rates`, within ``RATES_RTOL`` of the largest)."""
    t = plan.t
    v_ref, a_ref = joint_rates(t, plan.joints)
    for name, of, got, ref, unit in (
            ("joint_velocities", "joints", plan.joint_velocities, v_ref, "rad/s"),
            ("joint_accelerations", "joint_velocities", plan.joint_accelerations, a_ref, "rad/s^2")):
        off = np.abs(got - ref)
        bad = off > RATES_RTOL * np.abs(ref).max(initial=0.0) + 1e-9
        if bad.any():
            k, j = (int(v) for v in np.argwhere(bad)[0])
            _fail(source, f"samples.{name}[{k}][{j}]", f"the derivative of samples.{of} over samples.t (finite "
                  "differences, tooltransfer.planner.planning.plan.joint_rates)",
                  f"{got[k, j]:.6g} {unit} where they give {ref[k, j]:.6g} at t = {t[k]:.3f} s")


def check_plan(plan: Plan, source: str = "plan") -> None:
    """Check a solved (or violated) plan against itself and its task before running it: a bounded
    duration starting at 0 s; the task valid; the object path from the task's start to its target;
    joints within the Omni's limits whose forward kinematics give the tool poses; the tool never
    overlapping the planned object (nor at the start) nor an obstacle; tool speeds and accelerations
    within the task's ``timing`` limits; the planned tool path moving the object as planned through
    the push model (the mechanics in the plan's metrics); the joints' velocities and accelerations
    those the joints give on the plan's times (:func:`tooltransfer.planner.planning.plan.joint_rates`).

    Raises:
        PlanFileError: naming ``source`` (the file) and the field of the first problem
            (:class:`PlanLimitError` for the bounds ``--force`` does not lift).
    """
    t = plan.t
    if t.size < 2:
        raise PlanLimitError(source, "samples.t", "at least 2 samples", t.size)
    if t[-1] - t[0] > MAX_PLAN_DURATION:
        raise PlanLimitError(source, f"samples.t[{t.size - 1}]", f"a plan of at most {MAX_PLAN_DURATION:g} s (the "
                             "simulation's bound, --force or not)", f"{t[-1] - t[0]:.6g} s")
    if not 0.0 <= t[0] <= 1.0:
        _fail(source, "samples.t[0]", "a plan starting at 0 s", f"{t[0]:.6g} s")
    task = task_from_dict(plan.task, f"{source}: task")
    # the geometry (the replay takes the plan's own mechanics, :func:`_check_replay`; the obstacles are
    # checked against the tool path, not through the margin)
    setting = setting_from_task(task, mechanics=task_mechanics(task), margin=task.safety_margin)
    start, target = np.array(task.start), np.array(task.target)
    for k, point, name in ((0, start, "start"), (t.size - 1, target, "target")):
        off = float(np.hypot(*(plan.object_xy[k] - point)))
        if off > END_TOL:
            _fail(source, f"samples.object_xy[{k}]", f"the task's {name} {point.round(6).tolist()} m (within "
                  f"{1e3 * END_TOL:g} mm)", f"{plan.object_xy[k].round(6).tolist()} m, {1e3 * off:.3g} mm off")
    _check_joints(plan, source, setting.platform)
    _check_clear(plan, source, setting, start)
    _check_tool_rates(plan, source, task)
    _check_replay(plan, source, task, setting, start)
    _check_joint_rates(plan, source)


def plan_to_use(path: str | Path, force: bool, verb: str, doing: str, refused: str = "") -> Plan | None:
    """The plan file at ``path`` read and checked before a command uses it (``simulate`` runs it,
    ``export`` exports it): None, after one line saying why, for a plan that is not solved (a
    ``violated`` one goes on with ``force``); the checks of :func:`check_plan` refuse it, unless
    ``force``, with a warning (never past the simulation's own bounds, :class:`PlanLimitError`).
    ``verb`` and ``doing`` name the use ("runs", "running"; "exports", "exporting"); ``refused`` ends
    the line of a refusal."""
    import sys

    from tooltransfer.planner.planning.plan import read_plan

    plan = read_plan(path)
    if plan.status != "solved" and not (force and plan.status == "violated"):
        more = f" (--force {verb} it anyway)" if plan.status == "violated" else ""
        print(f"plan {path} is {plan.status}: {plan.reason}{more}{refused}")
        return None
    if plan.status == "violated":
        print(f"tooltransfer: warning: plan {path} is violated ({plan.reason}); {doing} it anyway (--force)",
              file=sys.stderr)
    try:  # the plan against itself and its task (a hand-edited plan may lie)
        check_plan(plan, str(path))
    except PlanFileError as exc:
        if not force or isinstance(exc, PlanLimitError):
            raise
        print(f"tooltransfer: warning: {exc}; {doing} it anyway (--force)", file=sys.stderr)
    return plan

