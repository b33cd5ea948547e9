"""A task's simulated scene as an MJCF file, and a plan replayed in MuJoCo's own viewer.

:func:`scene_mjcf` is the model the simulation runs (:func:`tooltransfer.tools.sim.mjcf.build_mjcf`:
the Omni carrying the task's tool, the puck, the obstacles, the table) with the task's object
settings, plus what a reader of the file wants to see: the target as a flat green disc (a site, which
touches nothing) and a keyframe ``start`` with the puck at the task's start and the arm at its start
joints (a plan's first sample, else the arm's zero pose). ``simulate --viewer``
(:func:`replay_in_viewer`) opens that model in ``mujoco.viewer`` and runs the plan's joint
references on it in real time.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.validation import check_array

if TYPE_CHECKING:
    from tooltransfer.planner.planning.plan import Plan
    from tooltransfer.problems.task import Task

#: Name of the keyframe of the start (``mujoco.mj_resetDataKeyframe`` with its id, or the viewer's
#: "Load key").
START_KEY = "start"
#: Name of the target's site.
TARGET_SITE = "target"


def scene_mjcf(task: Task, q0: ArrayLike | None = None) -> str:
    """The MJCF text of ``task``'s scene with the arm at ``q0`` (3,) [rad] (default zeros) in its
    ``start`` keyframe; compiles with ``mujoco.MjModel.from_xml_string``.

    Raises:
        InputError: ``q0`` of another shape or outside the platform's joint limits.
    """
    import mujoco

    from tooltransfer.planner.execution.simulate import task_sim_config
    from tooltransfer.planner.planning.setting import setting_from_task, task_mechanics
    from tooltransfer.tools.sim.mjcf import build_mjcf
    from tooltransfer.tools.sim.model import SimModel

    setting = setting_from_task(task, mechanics=task_mechanics(task), margin=task.safety_margin)
    q = np.zeros(3) if q0 is None else check_array(q0, "q0", shape=(3,))
    bad = setting.platform.limits.violated(q, 1e-6)
    if bad:
        raise InputError("q0", "joints within the platform's limits", f"{q.tolist()} (joint(s) "
                         f"{[j + 1 for j in bad]} outside)")
    config = task_sim_config(task)
    xml = build_mjcf(setting.tool, setting.platform, list(setting.obstacles), config)
    sim = SimModel(setting.tool, setting.platform, tuple(setting.obstacles), config, xml,
                   mujoco.MjModel.from_xml_string(xml))
    data = mujoco.MjData(sim.model)
    sim.set_configuration(data, np.asarray(task.start, dtype=np.float64), q)
    tx, ty = task.target
    site = (f'    <site name="{TARGET_SITE}" type="cylinder" pos="{tx!r} {ty!r} 0.0002" '
            f'size="{config.puck_radius!r} 0.0002" rgba="0.1 0.7 0.2 0.5"/>\n')
    key = (f'  <keyframe>\n    <key name="{START_KEY}" qpos="{_numbers(data.qpos)}" '
           f'ctrl="{_numbers(data.ctrl)}"/>\n  </keyframe>\n')
    head, _, _ = xml.replace("  <worldbody>\n", "  <worldbody>\n" + site, 1).rpartition("</mujoco>")
    return head + key + "</mujoco>\n"


def _numbers(values: NDArray[np.float64]) -> str:
    return " ".join(repr(float(v)) for v in values)


def display_problem() -> str | None:
    """Why MuJoCo's viewer cannot open here (no display, or ``mujoco.viewer`` does not load), or None."""
    if sys.platform not in ("darwin", "win32") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return "no display (neither DISPLAY nor WAYLAND_DISPLAY is set)"
    try:
        import mujoco.viewer  # noqa: F401  (glfw and an OpenGL library)
    except Exception as exc:  # any failure to load the viewer's libraries
        return f"mujoco.viewer does not load ({type(exc).__name__}: {exc})"
    return None


def check_viewer(option: str = "--viewer") -> None:
    """Raise :class:`InputError` naming ``option`` where MuJoCo's viewer cannot open (checked before
    any work)."""
    problem = display_problem()
    if problem:
        raise InputError(option, "a desktop session where MuJoCo's viewer can open a window "
                         "(--figure or --gif draw the execution without one)", problem)


def viewer_run(plan: Plan) -> tuple[Any, Any, NDArray[np.float64]]:
    """What the viewer runs: the compiled scene of ``plan`` (``mujoco.MjModel``), its data at the
    ``start`` keyframe (``mujoco.MjData``) and the actuators' controls of every physics step (n, 6)
    (the plan's joints and velocities as the simulation resamples them)."""
    import mujoco

    from tooltransfer.planner.planning.setting import setting_from_task, task_mechanics
    from tooltransfer.problems.task import task_from_dict
    from tooltransfer.tools.sim.reference import joint_reference

    task = task_from_dict(plan.task, "plan.task")
    model = mujoco.MjModel.from_xml_string(scene_mjcf(task, plan.joints[0]))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(START_KEY).id)
    platform = setting_from_task(task, mechanics=task_mechanics(task)).platform
    ref = joint_reference(plan.t, plan.joints, plan.joint_velocities, model.opt.timestep, platform)
    return model, data, np.hstack([ref.q, ref.qd])


def replay_in_viewer(plan: Plan) -> None:
    """Open ``plan``'s scene in ``mujoco.viewer`` and track its joints there in real time
    (:func:`viewer_run`); returns when the window is closed."""
    import time

    import mujoco
    import mujoco.viewer

    model, data, controls = viewer_run(plan)
    with mujoco.viewer.launch_passive(model, data) as viewer:
        start = time.perf_counter()
        for k, ctrl in enumerate(controls):
            if not viewer.is_running():
                return
            data.ctrl[:] = ctrl
            mujoco.mj_step(model, data)
            if k % 10 == 0:  # the window at 100 Hz, the physics at its own step
                viewer.sync()
                time.sleep(max(0.0, k * model.opt.timestep - (time.perf_counter() - start)))
        while viewer.is_running():
            viewer.sync()
            time.sleep(0.05)
