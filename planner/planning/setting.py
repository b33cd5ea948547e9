"""The world a plan acts in, built once from a task: :class:`Setting` and :func:`setting_from_task`.

A :class:`Setting` holds what the task fixes about the physical system: the tool, the Omni carrying it,
the object (a :class:`~tooltransfer.tools.objects.DiscObject`, which validates its radius), the push
mechanics, the obstacles and the safety margin the plan can keep. It holds no planning option: the
share of the friction cone a plan may use and the contact's margins are the OE variants' options
(:class:`~tooltransfer.planner.planning.oe.qp_options.QPOptions`,
:class:`~tooltransfer.planner.planning.oe.mapping_variant.MappingOptions`), the switch clearance the task's
``ss`` section. ``solve``, the closed loop, the figures, ``simulate`` and the benchmarks build it with
:func:`setting_from_task` and pass it down, so they plan for the same world.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from tooltransfer.errors import InputError
from tooltransfer.problems.task import (
    SAFETY_MARGIN,
    Task,
    faces_derived,
    resolve,
    task_obstacles,
    task_origin,
    task_platform,
    task_tool,
)
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, DiscObject, Obstacle
from tooltransfer.tools.omni.dh import D1, D_TOOL, L1, L2, THETA_TOOL
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pushing.mechanics import PLATFORM_MECHANICS, PushMechanics

if TYPE_CHECKING:
    from tooltransfer.planner.learning.skills import Skills


@dataclass(frozen=True, eq=False)
class Setting:
    """The world a plan acts in, as one planning input. Two settings are equal when they describe
    the same world (:meth:`describe`, the mechanics and the margin).

    Attributes:
        tool: the tool the Omni carries.
        platform: the Omni carrying ``tool`` (its ``a_t``, base, joint limits).
        obj: the pushed object, a disc (:class:`DiscObject`, which validates its radius: the one place).
        mechanics: the push model's parameters (tool-object friction ``mu``, limit-surface ``c``).
        obstacles: discs and convex shapely polygons in the world [m].
        margin: safety margin [m] kept from the obstacles beyond the object's radius (the one the
            plan can keep: :func:`effective_margin`; by default the task schema's ``safety_margin``).
    """

    tool: Tool
    platform: OmniPlatform
    obj: DiscObject
    mechanics: PushMechanics = PLATFORM_MECHANICS
    obstacles: tuple[Obstacle, ...] = ()
    margin: float = SAFETY_MARGIN

    def __post_init__(self) -> None:
        if not isinstance(self.obj, DiscObject):
            raise InputError("setting.obj", "a DiscObject", type(self.obj).__name__)
        if not isinstance(self.mechanics, PushMechanics):
            raise InputError("setting.mechanics", "a PushMechanics", type(self.mechanics).__name__)
        m = self.margin
        if not isinstance(m, int | float | np.floating) or not np.isfinite(m) or m < 0:
            raise InputError("setting.margin", "a finite length [m] >= 0", repr(m))
        object.__setattr__(self, "margin", float(m))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Setting):
            return NotImplemented
        return (self.describe(), self.mechanics, self.margin) == (other.describe(), other.mechanics, other.margin)

    __hash__ = None  # type: ignore[assignment]  # equal settings need not be the same objects

    @property
    def radius(self) -> float:
        """The object's radius [m] (``obj.radius``)."""
        return self.obj.radius

    def with_obstacles(self, obstacles: Sequence[Obstacle]) -> Setting:
        """The same setting with other obstacles."""
        return replace(self, obstacles=tuple(obstacles))

    def describe(self) -> dict[str, Any]:
        """The setting as plain JSON values, as a plan file records it: ``platform`` (the DH table,
        base, joint limits), ``object`` (``radius`` [m]), ``tool`` (outline and faces [m, rad]) and
        ``obstacles`` (discs and polygons [m]). Two settings that describe alike plan alike, up to
        the mechanics and the margin (:attr:`mechanics`, :attr:`margin`)."""
        p, tool = self.platform, self.tool
        return {
            "platform": {
                "dh": [
                    {"joint": 1, "alpha": -np.pi / 2, "a": 0.0, "d": D1, "theta": "q1"},
                    {"joint": 2, "alpha": 0.0, "a": L1, "d": 0.0, "theta": "q2"},
                    {"joint": 3, "alpha": 0.0, "a": L2, "d": 0.0, "theta": "q3"},
                    {"joint": "tool", "alpha": 0.0, "a": p.a_t, "d": D_TOOL, "theta": THETA_TOOL},
                ],
                "base_xy": list(p.base_xy), "base_yaw": p.base_yaw,
                "table_height": p.table_height, "a_t": p.a_t,
                "joint_limits": {"lower": list(p.limits.lower), "upper": list(p.limits.upper)},
            },
            "object": {"radius": self.radius},
            "tool": {
                "name": tool.name, "outline": np.asarray(tool.outline.exterior.coords)[:-1].tolist(),
                "faces": [{"name": f.name, "segment": [f.start.tolist(), f.end.tolist()],
                           "push_angle": f.push_angle, "theta_b": f.theta_b,
                           "contact_range": list(f.contact_range)} for f in tool.faces],
            },
            "obstacles": [
                {"kind": "disc", "centre": o.centre.tolist(), "radius": o.radius} if isinstance(o, Disc)
                else {"kind": "polygon", "vertices": np.asarray(o.exterior.coords)[:-1].tolist()}
                for o in self.obstacles
            ],
        }


def task_skills(task: Task, task_path: str | Path | None = None, *, need_ss: bool = True) -> Skills:
    """The skills ``task`` names: learned from its dataset (cached; the SS skill only if ``need_ss``)
    or read from its skills file (relative to ``task_path``, by default the task's file:
    :func:`~tooltransfer.problems.task.task_origin`).

    Raises:
        InputError: a missing dataset or skills file, or a skills file learned with another ``k``
            than the task's ``oe.k``.
    """
    from tooltransfer.planner.learning.skills import learn_skills, load_skills_file

    task_path = task_origin(task, task_path)
    if task.skills.file is not None:
        skills = load_skills_file(resolve(task_path, task.skills.file))
        if "k" in task.oe.model_fields_set and task.oe.k != skills.oe.k:
            raise InputError("oe.k", f"the skills file's k = {skills.oe.k} (or learn the skills again)", task.oe.k)
        return skills
    folder = resolve(task_path, task.skills.dataset or "")
    return learn_skills(folder, task.oe.k, task.ss.virtual_motion, with_ss=need_ss)


def task_mechanics(task: Task, skills: Skills | None = None) -> PushMechanics:
    """The push model's parameters: the task's ``object.mechanics`` override, else those identified
    with the skills, else the platform's nominal values (:data:`PLATFORM_MECHANICS`)."""
    spec = task.object.mechanics
    if spec is not None:
        return PushMechanics(spec.mu, spec.c, "task")
    identified = getattr(skills, "mechanics", None)
    return identified if isinstance(identified, PushMechanics) else PLATFORM_MECHANICS


def effective_margin(task: Task, obstacles: Sequence[Obstacle]) -> float:
    """The safety margin [m] the plan can keep: the task's ``safety_margin``, reduced to the object's
    clearance from the nearest obstacle at the start or the target when that is smaller (an object
    that starts touching an obstacle keeps at least its starting clearance; the plan's metrics
    report the margin used).

    Raises:
        InputError: the object overlaps an obstacle at the start or the target.
    """
    import shapely

    r = task.object.radius
    margin = task.safety_margin
    for field, point in (("start", task.start), ("target", task.target)):
        disc = shapely.Point(point).buffer(r, quad_segs=64)
        for i, o in enumerate(obstacles):
            shape = o.polygon() if isinstance(o, Disc) else o
            gap = float(shapely.distance(disc, shape))
            if gap == 0.0 and shapely.intersection(disc, shape).area > 1e-10:
                raise InputError(field, f"an object position clear of obstacles[{i}] (the object of radius "
                                 f"{r} m overlaps it)", list(point))
            margin = min(margin, gap)
    return margin


def setting_from_task(task: Task, skills: Skills | None = None, task_path: str | Path | None = None, *,
                      mechanics: PushMechanics | None = None, margin: float | None = None) -> Setting:
    """The :class:`Setting` of ``task``: its tool, platform, obstacles and object, the push mechanics
    (``mechanics`` when given, e.g. those a plan file records; else :func:`task_mechanics`: the task's
    override, else the ``skills``' identified ones, else the platform's) and the safety margin
    (``margin`` [m] when given, e.g. to check a plan file whatever its task's obstacles; else the one
    the plan can keep, :func:`effective_margin`).

    Without ``skills`` or ``mechanics``, a task without a mechanics override learns or reads its
    skills (:func:`task_skills`, relative to ``task_path``; the SS skill is not learned) for their
    mechanics.

    Raises:
        InputError: the object overlaps an obstacle at the start or the target, or the skills
            cannot be had (:func:`task_skills`).
    """
    tool = task_tool(task)
    platform = task_platform(task, tool)
    obstacles = tuple(task_obstacles(task))
    if margin is None:
        margin = effective_margin(task, obstacles)
    if mechanics is None:
        if skills is None and task.object.mechanics is None:
            skills = task_skills(task, task_path, need_ss=False)
        mechanics = task_mechanics(task, skills)
    if faces_derived(task):  # faces derived from the outline get the friction cone of these mechanics
        tool = task_tool(task, friction=mechanics.mu)
    return Setting(tool, platform, DiscObject(task.object.radius), mechanics, obstacles, margin)


__all__ = ["Setting", "effective_margin", "setting_from_task", "task_mechanics", "task_skills"]
