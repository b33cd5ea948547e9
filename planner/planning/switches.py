"""Switch planners for :func:`tooltransfer.planner.planning.assemble.assemble`: the tool path between two pushes while
the object rests, by variant.

* ``arch``: the geometric reference (:mod:`tooltransfer.planner.planning.ss.arch_variant`): back off, arch round the
  object (and disc obstacles; a polygon obstacle is taken as its enclosing disc), approach;
* ``dmp``: the SS skill generalized by recombination (paper section III.B, eq. 18;
  :func:`tooltransfer.planner.planning.ss.recombine`); it may penetrate the object or an obstacle: the penetration is
  measured exactly (shapely) and reported, as the paper's method would produce it;
* ``opt``: the CasADi NLP near the ``dmp`` path with non-penetration and reach
  (:func:`tooltransfer.planner.planning.ss.optimize`), checked exactly with shapely; never returns a penetrating path.

Each planner is ``planner(object_xy (2,), face_a, pose_a (3,), face_b, pose_b (3,)) -> SwitchPath``
(:data:`tooltransfer.planner.planning.assemble.SwitchPlanner`, :class:`tooltransfer.planner.planning.ss.SwitchPath`);
``object_clearance`` is the least tool-object distance [m] over the middle of the switch (away from the
two contacts, where the tool must touch), ``obstacle_clearance`` the least tool-obstacle distance [m]
(infinite without obstacles), and ``object_penetration``, ``obstacle_penetration`` the largest
penetration depths [m] over the whole switch, measured exactly on the swept outline.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.planning.assemble import SwitchPlanner
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.ss import OptOptions, SwitchPath, SwitchSkill, SwitchTask, optimize, recombine
from tooltransfer.planner.planning.ss.arch_variant import NoArch, swept_clearance, switch_path
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.pose import rotation

#: How a skill variant solves one switch: ``solve(skill, task) -> SwitchPath``.
SkillSolver = Callable[[SwitchSkill, SwitchTask], SwitchPath]


def enclosing_disc(poly: shapely.Polygon) -> Disc:
    """The disc about the vertices' mean that holds every vertex of ``poly``."""
    ring = np.asarray(poly.exterior.coords)[:-1]
    c = ring.mean(axis=0)
    return Disc(c, float(np.linalg.norm(ring - c, axis=1).max()))


def densify(xy: NDArray[np.float64], step: float) -> NDArray[np.float64]:
    """The polyline ``xy`` (K, 2) [m] resampled at most ``step`` [m] apart along its length."""
    seg = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(2, int(np.ceil(s[-1] / step)) + 1)
    u = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(u, s, xy[:, j]) for j in range(2)])


def contact_fraction(tool: Tool, face: str, obj: NDArray[np.float64], pose: NDArray[np.float64],
                     radius: float) -> float:
    """Fraction along ``face`` (in its contact range) where the tool at ``pose`` (3,) touches the disc
    of ``radius`` [m] centred at ``obj`` (2,) [m]: the foot of the perpendicular from the centre."""
    f = tool.face(face)
    local = rotation(-float(pose[2])) @ (np.asarray(obj, float) - np.asarray(pose[:2], float))
    d = f.end - f.start
    s = float((local - radius * f.normal - f.start) @ d / (d @ d))
    return float(np.clip(s, *f.contact_range))


def arch_planner(setting: Setting, clearance: float) -> SwitchPlanner:
    """The ``arch`` switch planner in ``setting`` (``clearance`` [m] from the object and the obstacles)."""
    tool, platform, radius = setting.tool, setting.platform, setting.radius
    discs = [o if isinstance(o, Disc) else enclosing_disc(o) for o in setting.obstacles]

    def plan(obj: NDArray[np.float64], face_a: str, pose_a: NDArray[np.float64], face_b: str,
             pose_b: NDArray[np.float64]) -> SwitchPath:
        ends = joint_path(platform, np.vstack([pose_a[:2], pose_b[:2]]))
        if np.any(ends.refused):
            return SwitchPath("arch", "infeasible", f"a contact pose of the switch {face_a} -> {face_b} "
                              f"(object at {np.round(obj, 4).tolist()} m) is outside the Omni's reach")
        da = pose_a[2] + tool.face(face_a).push_angle
        db = pose_b[2] + tool.face(face_b).push_angle
        try:
            xy = switch_path(tool, platform, obj, pose_a, da, pose_b, db, clearance=clearance, obstacles=discs,
                             radius=radius)
        except NoArch as exc:
            return SwitchPath("arch", "infeasible", str(exc))
        dense = densify(xy, 0.0005)
        reach = joint_path(platform, dense)
        bad = np.flatnonzero(reach.refused)
        if bad.size:
            return SwitchPath("arch", "infeasible", f"the arch leaves the Omni's reach at "
                              f"{np.round(dense[bad[0]], 4).tolist()} m (object at {np.round(obj, 4).tolist()} m)")
        near = min((swept_clearance(tool, platform, dense, o.centre, o.radius) for o in discs), default=np.inf)
        return SwitchPath("arch", "solved", xy=xy,
                          object_clearance=swept_clearance(tool, platform, dense[8:-8], obj, radius),
                          obstacle_clearance=float(near), object_penetration=0.0, obstacle_penetration=0.0)

    return plan


def skill_planner(variant: str, solve: SkillSolver, skill: SwitchSkill, setting: Setting) -> SwitchPlanner:
    """The switch planner of an SS skill variant named ``variant``: each switch posed as a
    :class:`SwitchTask` in ``setting`` (the contact fractions where the two poses touch the object)
    and solved by ``solve(skill, task)``; the path's ends are the exact contact poses."""
    tool, platform, radius, obs = setting.tool, setting.platform, setting.radius, setting.obstacles

    def plan(obj: NDArray[np.float64], face_a: str, pose_a: NDArray[np.float64], face_b: str,
             pose_b: NDArray[np.float64]) -> SwitchPath:
        s_a, s_b = (contact_fraction(tool, f, obj, p, radius) for f, p in ((face_a, pose_a), (face_b, pose_b)))
        try:
            task = SwitchTask(tool, face_a, face_b, np.asarray(obj, float), s_from=s_a, s_to=s_b,
                              obj=setting.obj, obstacles=obs, platform=platform)
        except InputError as exc:  # e.g. a "switch" of one face to where it already touches
            return SwitchPath(variant, "infeasible", f"{variant} switch: {exc}")
        res = solve(skill, task)
        res = replace(res, obstacle_clearance=float(res.obstacle_clearance) if obs else float("inf"))
        if not res.ok:
            return replace(res, status="infeasible", reason=f"{variant} switch: {res.reason}")
        # the skill's path starts and ends at the exact contact poses the push plan uses
        gap = max(float(np.hypot(*(res.xy[0] - pose_a[:2]))), float(np.hypot(*(res.xy[-1] - pose_b[:2]))))
        return replace(res, info={**res.info, "contact_gap": gap})

    return plan


def dmp_planner(skill: SwitchSkill, setting: Setting) -> SwitchPlanner:
    """The ``dmp`` switch planner: the SS skill recombined (eq. 18); penetration measured, not avoided."""
    return skill_planner("dmp", recombine, skill, setting)


def opt_planner(skill: SwitchSkill, setting: Setting, clearance: float, n_knots: int) -> SwitchPlanner:
    """The ``opt`` switch planner: the CasADi NLP near the ``dmp`` path with ``n_knots`` knots, keeping
    ``clearance`` [m] over the middle of the switch (1 um stands for "touching allowed": the NLP needs
    a positive margin)."""
    options = OptOptions(n_knots=n_knots, margin=max(clearance, 1e-6))
    return skill_planner("opt", lambda sk, task: optimize(sk, task, options), skill, setting)


def with_fallback(primary: SwitchPlanner, fallback: SwitchPlanner, name: str) -> SwitchPlanner:
    """``primary``, and where it finds no path, ``fallback`` (the path's ``fallback`` is True; the reason
    of a failure names both)."""

    def plan(obj: NDArray[np.float64], face_a: str, pose_a: NDArray[np.float64], face_b: str,
             pose_b: NDArray[np.float64]) -> SwitchPath:
        first = primary(obj, face_a, pose_a, face_b, pose_b)
        if first.status == "solved":
            return first
        second = fallback(obj, face_a, pose_a, face_b, pose_b)
        if second.status == "solved":
            return replace(second, fallback=True)
        return replace(first, status="infeasible", reason=f"{first.reason}; the {name} fallback: {second.reason}")

    return plan
