"""The ``dmp`` variant: generalize the SS skill to a new tool, contacts and object by recombination
(paper section III.B, steps 5-6; docs/design.md section 6).

For the task's contacts ``(p_A, q_A)`` and ``(p_B, q_B)`` (with the headings the Omni imposes there):

5. the new virtual object motion ``x^o`` from ``q_A`` to ``q_B`` round the placed object (the skill's
   kind and clearance) and its forcing term ``f^o`` (a DMP with the skill's basis, gains and phase
   fitted to it);
6. ``k1 = diag(dx^t_new / dx^t_demo)`` per axis, the ratio of the new to the demonstrated pure tool
   displacement ``-R_B (p_B - p_A)`` (1 on an axis the demonstrations barely moved along, below
   ``min_shift``); ``k2 = I`` because ``f^o`` is fitted to the new ``x^o`` itself (scaling it by the
   ratio of displacements again would count the change twice); ``f = k1 f^t + k2 f^o`` (18), rolled out
   from ``x_o = q_A`` to ``g = q_B - R_B (p_B - p_A)``: the path of the tool point ``p_A``.

A DMP approaches its goal asymptotically; the few micrometres left at ``t = T`` are removed by adding
``(g - x(T)) s(t)`` with the minimum-jerk ``s`` (reported as ``info["end_correction"]``), so the path
starts and ends exactly at the contacts. The tool centre point follows from the heading the Omni
imposes (fixed point, :func:`tooltransfer.tools.omni.heading.centre_path`). The swept tool is then measured
exactly against the object and the obstacles (:mod:`tooltransfer.planner.planning.ss.verify`): this variant does not
avoid penetration, it reports it.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InfeasibleError, InputError
from tooltransfer.planner.learning.switch_skill import SwitchSkill
from tooltransfer.planner.learning.virtual_motion import Way, min_jerk, virtual_motion
from tooltransfer.planner.planning.ss.recombination import dmp_settings, linear_recombination, recombination_map
from tooltransfer.planner.planning.ss.result import SwitchPath
from tooltransfer.planner.planning.ss.switch_task import SwitchTask
from tooltransfer.planner.planning.ss.verify import sweep_checks
from tooltransfer.tools.omni.heading import centre_path, heading, rot
from tooltransfer.tools.omni.ik import joint_path

#: Share of the steps at each end of a path that count as "near the contacts" for the clearance report.
END_SHARE = 0.15


def scale_factors(new: NDArray[np.float64], demo: NDArray[np.float64], min_shift: float = 1e-3) -> NDArray[np.float64]:
    """Per-axis ratio ``new / demo`` (2,), 1 where ``|demo| < min_shift`` [m]."""
    k = np.ones(2)
    big = np.abs(demo) >= min_shift
    k[big] = new[big] / demo[big]
    return k


def middle_steps(n_steps: int, share: float = END_SHARE) -> NDArray[np.bool_]:
    """Mask (n_steps,) of the steps away from the two contacts (the middle ``1 - 2 share``)."""
    k = np.arange(n_steps)
    lo = int(np.ceil(share * n_steps))
    return (k >= lo) & (k < n_steps - lo)


def measure(path: SwitchPath, task: SwitchTask) -> SwitchPath:
    """``path`` with its clearances and penetrations measured exactly (shapely,
    :mod:`tooltransfer.planner.planning.ss.verify`)."""
    from dataclasses import replace

    obj, obs = sweep_checks(task.tool, path.xy, path.yaw, task.shape, task.obstacles)
    mid = middle_steps(path.xy.shape[0] - 1)
    return replace(
        path,
        object_penetration=obj.max_penetration,
        object_clearance=obj.min_clearance(mid),
        obstacle_penetration=max((o.max_penetration for o in obs), default=0.0),
        obstacle_clearance=min((o.min_clearance() for o in obs), default=float("inf")),
    )


def recombine(
    skill: SwitchSkill, task: SwitchTask, *, n_samples: int = 100, way: Way | float = "short",
    measured: bool = True, fast: bool = True,
) -> SwitchPath:
    """The ``dmp`` switch path of ``task`` (module docstring) at ``n_samples`` times, measured with
    shapely unless ``measured`` is False; never raises for an impossible switch (status
    ``infeasible`` with the reason). ``fast``: the fit of ``f^o`` and the rollout as one cached
    linear map per time grid (:mod:`tooltransfer.planner.planning.ss.recombination`; the same numbers to round-off),
    when the skill's DMPs are linear (scaling ``"none"``); False: :meth:`tooltransfer.dmp.primitive.DMP.fit` and
    ``rollout`` on every call."""
    t0 = time.perf_counter()
    if not isinstance(skill, SwitchSkill):
        raise InputError("skill", "a SwitchSkill", type(skill).__name__)
    if not isinstance(n_samples, int) or n_samples < 5:
        raise InputError("n_samples", "an integer >= 5", repr(n_samples))
    try:
        a, b = task.contact("from"), task.contact("to")
    except InfeasibleError as exc:
        return SwitchPath("dmp", "infeasible", exc.reason)
    T = task.duration or skill.tau
    t = np.linspace(0.0, T, n_samples)
    q_a, q_b, p_a, p_b = a.object_point, b.object_point, a.tool_point, b.tool_point
    x_virtual = virtual_motion(skill.virtual, t, q_a, q_b, task.shape, clearance=skill.clearance, way=way) - q_a
    tool_shift = -rot(b.pose.yaw) @ (p_b - p_a)
    k1 = scale_factors(tool_shift, skill.tool_shift)
    k2 = np.ones(2)
    g = (q_b - q_a) + tool_shift
    if fast and linear_recombination(skill.dmp_t) and dmp_settings(skill.dmp_t) == dmp_settings(skill.dmp_x):
        # the same maths as below as one cached linear map per grid (tooltransfer.planner.planning.ss.recombination)
        x = recombination_map(skill.dmp_t, t).path(skill.dmp_t.weights * k1, x_virtual * k2, g)
    else:
        dmp_o = skill.new_dmp().fit(t, x_virtual)
        w = skill.dmp_t.weights * k1 + dmp_o.weights * k2  # eq. (18), per axis
        x = skill.dmp_t.rollout(t, x0=np.zeros(2), g=g, tau=T, weights=w).x
    corr = g - x[-1]
    x = x + corr * min_jerk(t / T)[:, None]
    xy = centre_path(task.omni, x + q_a, p_a)
    yaw = heading(task.omni, xy)
    reach = joint_path(task.omni, xy).violation
    path = SwitchPath(
        "dmp", "solved", "", t, xy, yaw, a, b,
        info={
            "k1": k1, "k2": k2, "end_correction": float(np.hypot(*corr)), "virtual": skill.virtual,
            "x_virtual": x_virtual + q_a, "x_contact_point": x + q_a,
            "end_error": float(max(np.hypot(*(xy[0] - a.pose.position)), np.hypot(*(xy[-1] - b.pose.position)))),
            "reach_violation": float(np.max(reach)),
        },
    )
    if measured:
        path = measure(path, task)
    path.info["time"] = time.perf_counter() - t0
    return path
