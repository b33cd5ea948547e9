"""Task files: what a user asks the planner to do, as a pydantic schema (SI units throughout).

A task names the tool (a library name or an inline definition), the object, its start and target,
obstacles (discs and convex polygons), the safety margin, the Omni platform, where the skills
come from (a demonstration dataset or a saved skills file), the variants to run (``oe: mapping|qp``,
``ss: dmp|opt``), solver options and time scaling. :func:`load_task` reads a YAML (or JSON) file
and reports any error with the file, the field path and what was expected; ``tooltransfer schema``
prints :func:`task_json_schema` for editors.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Final, Literal

import numpy as np
import shapely
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator, model_validator

from tooltransfer.errors import InputError
from tooltransfer.problems.variants import (
    MAPPING_K,
    SAFETY_MARGIN,
    VIRTUAL_MOTION,
    OEVariant,
    SSVariant,
    VirtualMotion,
)
from tooltransfer.timing import min_jerk_duration as min_jerk_time
from tooltransfer.tools.errors import ToolSpecError, UnknownToolError

if TYPE_CHECKING:
    from tooltransfer.tools.model import Tool
    from tooltransfer.tools.objects import Obstacle as ObstacleShape
    from tooltransfer.tools.omni.platform import OmniPlatform

FORMAT: Final = "tooltransfer.task/1"

# strict: a YAML true/false or a quoted number is a wrong type, not 1.0 / 0.0 (ints are still taken)
Finite = Annotated[float, Field(allow_inf_nan=False, strict=True)]
# every number is bounded (the bounds are in the JSON schema, ``tooltransfer schema``): a table-top
# task on the Omni needs nothing beyond them, and larger values make a solve allocate or run without end
Angle = Annotated[float, Field(ge=-7.0, le=7.0, allow_inf_nan=False, strict=True, description="[rad], |a| <= 7")]
# table-top coordinates: within 10 m of the origin (huge values overflow the geometry downstream)
Coordinate = Annotated[float, Field(ge=-10.0, le=10.0, allow_inf_nan=False, strict=True)]
Point = Annotated[tuple[Coordinate, Coordinate], Field(description="(x, y) in the world frame [m], |x|, |y| <= 10")]
Length = Annotated[float, Field(ge=0.0, le=0.2, allow_inf_nan=False, strict=True)]  # a length on a tool [m]


#: Longest plan a task may ask for [s] (``simulate`` refuses plans of more than 1800 s): the plan
#: samples its approach, switches and retreat at :data:`PLAN_RATE`, so this bounds its samples too.
MAX_PLAN_DURATION = 900.0
#: Sample rate of a plan's approach, switches and retreat [Hz]
#: (:func:`tooltransfer.planner.planning.assemble.assemble`).
PLAN_RATE = 100.0
#: Largest push-sequence search of the ``qp`` variant (:func:`push_search_steps`; a few seconds at most).
MAX_SEARCH_STEPS = 200_000
#: Longest task name [characters] (it names output files: ``plan_<name>.png``).
MAX_NAME = 100
MAX_TEXT = 4000


class TaskFileError(InputError):
    """A task file is unreadable or invalid; names the file, the field path and what was expected."""

    def __init__(self, path: str, field: str, expected: str, got: object | None = None) -> None:
        from tooltransfer.yaml_file import clip

        self.path = path
        # a value echoed in the message is cut at 100 characters (a field name at 200): one line, however
        # large what the file holds
        super().__init__(f"{path}: {clip(field, 200)}", expected, None if got is None else clip(got))


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class DiscObstacle(_Model):
    """A round obstacle."""

    kind: Literal["disc"] = "disc"
    centre: Point
    radius: float = Field(gt=0, le=1.0, allow_inf_nan=False, strict=True, description="[m]")


class PolygonObstacle(_Model):
    """A convex polygonal obstacle."""

    kind: Literal["polygon"] = "polygon"
    vertices: list[Point] = Field(min_length=3, max_length=64, description="convex polygon, either orientation [m]")

    @field_validator("vertices")
    @classmethod
    def _convex(cls, v: list[tuple[float, float]]) -> list[tuple[float, float]]:
        poly = shapely.Polygon(v)
        if not poly.is_valid or poly.area <= 0:
            raise ValueError("a simple polygon with positive area")
        if abs(poly.convex_hull.area - poly.area) > 1e-9 * poly.area:
            raise ValueError("a convex polygon")
        return v


Obstacle = Annotated[DiscObstacle | PolygonObstacle, Field(discriminator="kind")]


Expression = Annotated[str, Field(max_length=100)]


class InlineFace(_Model):
    name: str = Field(min_length=1, max_length=64)
    segment: tuple[Point, Point]
    push_angle: Angle | Expression = Field(description="[rad] in the tool frame; numbers or 'pi' expressions")
    theta_b: Angle | Expression = Field(description="cone half-angle [rad], in (0, pi/2)")
    contact_range: tuple[Length, Length] | None = None


class InlineTool(_Model):
    """A tool defined in the task itself (same fields as the library's YAML files; without ``faces`` the
    faces are derived from the outline for the task's object, :mod:`tooltransfer.tools.derive`)."""

    name: str = Field(min_length=1, max_length=MAX_NAME)
    a_t: float = Field(gt=0, le=0.2, allow_inf_nan=False, strict=True,
                       description="tool length of Table I's tool row [m]")
    outline: list[Point] = Field(min_length=3, max_length=256, description="simple polygon in the tool frame [m]")
    faces: list[InlineFace] | None = Field(None, min_length=1, max_length=8,
                                           description="none: derived from the outline")
    description: str = Field("", max_length=MAX_TEXT)
    notes: str = Field("", max_length=MAX_TEXT)


class MechanicsSpec(_Model):
    """The push model's parameters (docs/design.md section 10), overriding the ones identified from the
    demonstrations (or the platform's nominal values when none were identified)."""

    mu: float = Field(gt=0, le=10, allow_inf_nan=False, strict=True,
                      description="Coulomb friction coefficient between the tool and the object")
    c: float = Field(gt=0, le=2, allow_inf_nan=False, strict=True,
                     description="limit-surface ratio m_max / (R f_max) of the object on the table "
                                 "(2/3 uniform pressure, 1 a rim)")


class ObjectSpec(_Model):
    """The pushed object: a disc (the paper's puck)."""

    radius: float = Field(0.0175, ge=0.001, le=0.2, allow_inf_nan=False, strict=True, description="[m]")
    mass: float = Field(0.02, gt=0, le=10.0, allow_inf_nan=False, strict=True,
                        description="[kg], for the simulated platform")
    friction: float = Field(0.3, gt=0, le=5.0, allow_inf_nan=False, strict=True,
                            description="sliding friction coefficient against the table")
    mechanics: MechanicsSpec | None = Field(
        None, description="push model override (default: identified with the skills, else mu 0.8, c 0.59)")


class LimitsSpec(_Model):
    lower: tuple[Angle, Angle, Angle] = Field(description="(q1, q2, q3) [rad], Table I convention")
    upper: tuple[Angle, Angle, Angle] = Field(description="(q1, q2, q3) [rad]")


class PlatformSpec(_Model):
    """Placement of the Omni; omitted fields take the defaults of
    :class:`tooltransfer.tools.omni.platform.OmniPlatform`."""

    base_xy: Point = (0.0, 0.0)
    base_yaw: float = Field(float(np.pi / 2), ge=-7.0, le=7.0, allow_inf_nan=False, strict=True,
                            description="[rad]; pi/2 points q1 = 0 forward (+y)")
    table_height: float = Field(0.0, ge=-1.0, le=1.0, allow_inf_nan=False, strict=True,
                                description="height of the pushing plane in the base frame [m]")
    limits: LimitsSpec | None = None


class SkillsSpec(_Model):
    """Where the skills come from: a demonstration dataset (learned and cached) or a skills file."""

    dataset: str | None = Field(None, min_length=1, max_length=4096,
                                description="dataset folder, relative to the task file")
    file: str | None = Field(None, min_length=1, max_length=4096,
                             description="saved skills file, relative to the task file")

    @model_validator(mode="after")
    def _one(self) -> SkillsSpec:
        if (self.dataset is None) == (self.file is None):
            raise ValueError("exactly one of 'dataset' and 'file'")
        return self


class Variants(_Model):
    oe: OEVariant = Field("qp", description="OE condensing: the paper's mapping or the QP search")
    ss: SSVariant = Field(
        "opt", description="switch paths: the CasADi NLP (default), DMP recombination (the paper) or the "
        "geometric arch (a reference)",
    )


class OEOptions(_Model):
    """Options of OE condensing (:class:`tooltransfer.planner.planning.oe.QPOptions` takes its fields from here)."""

    # the one source of these defaults, bounds and descriptions: QPOptions and MappingOptions reuse
    # the fields, FaceFrame its cone fraction (tests/test_options_once.py)

    # the bounds keep one solve within seconds and well under 1 GB (figures at the bounds in
    # benchmarks/README.md); the push-sequence search grows as faces^max_pushes x segments
    # (:data:`MAX_SEARCH_STEPS`); each candidate is a QP
    n_samples: int = Field(120, ge=10, le=2000, strict=True,
                           description="constraint-grid samples of the final fit (violations are measured 10x denser)")
    n_basis: int = Field(25, ge=1, le=100, strict=True,
                         description="basis functions per dimension of the condensed DMP")
    segments: int = Field(10, ge=1, le=50, strict=True, description="switch times lie on this many equal phases")
    max_pushes: int = Field(4, ge=1, le=8, strict=True,
                            description="longest push sequence searched (the search, faces^max_pushes x segments, "
                                        f"is bounded at {MAX_SEARCH_STEPS} steps for the task's tool)")
    candidates: int = Field(3, ge=1, le=20, strict=True, description="push sequences scored by a QP each")
    switch_price: float = Field(2e-7, ge=0, le=1.0, allow_inf_nan=False, strict=True,
                                description="cost per face change [m^2]")
    k: float = Field(MAPPING_K, gt=0, lt=1, allow_inf_nan=False, strict=True,
                     description="adjusting factor of the mappings (6)-(7)")
    tube: float = Field(0.01, gt=0, le=1.0, allow_inf_nan=False, strict=True,
                        description="tube radius around the universal path, mapping variant [m]")
    friction_cone_fraction: float = Field(
        0.5, gt=0, le=1, allow_inf_nan=False, strict=True,
        description="share of the friction cone's half-angle atan(mu) the planned object directions may use")
    friction_cone_fraction_max: float = Field(
        0.95, gt=0, le=1, allow_inf_nan=False, strict=True,
        description="widest share of the friction cone's half-angle the guided search may use where no plan "
                    "keeps to friction_cone_fraction: after friction_cone_fraction, 0.8 where this is wider, "
                    "this share last (set it to friction_cone_fraction or lower never to widen). A plan records "
                    "the share it used (metric friction_cone_fraction); near 1 it has little margin for mu")
    guided_budget: int = Field(
        4000, ge=100, le=1_000_000, strict=True,
        description="expansions of the guided search per attempt (cone share and contact span) "
                    "(its coverage grows with it)")
    contact_margin: float = Field(
        0.0002, ge=0, le=0.05, allow_inf_nan=False, strict=True,
        description="distance the contact keeps from the ends of a face's usable range [m]")
    contact_span: float = Field(
        0.012, gt=0, le=0.2, allow_inf_nan=False, strict=True,
        description="longest stretch of a face the contact may use, about its middle [m] (the reach "
                    "is planned for the tool at both ends of it)")
    max_contacts: int = Field(6, ge=1, le=10, strict=True,
                              description="most contacts (re-contacts + 1) one push may use")
    self_consistency_tol: float = Field(
        1e-4, gt=0, le=0.01, allow_inf_nan=False, strict=True,
        description="largest distance between the planned object path and the push model's replay "
                    "of the planned tool path for a solved plan [m]")


class SSOptions(_Model):
    """Options of the switch paths."""

    # the one source of these defaults: the opt variant's OptOptions takes n_knots from here

    virtual_motion: VirtualMotion = VIRTUAL_MOTION
    n_knots: int = Field(40, ge=4, le=100, strict=True,
                         description="knots of a switch path (the CasADi NLP's size grows with it)")
    clearance: float = Field(
        0.002, ge=0, le=0.05, allow_inf_nan=False, strict=True,
        description="tool-object and tool-obstacle clearance kept during switches [m]"
    )


class Timing(_Model):
    """Time scaling of the executed plan (slower limits make longer plans: a task whose straight push
    alone would take more than :data:`MAX_PLAN_DURATION` is refused)."""

    max_tool_speed: float = Field(0.05, ge=0.005, le=1.0, allow_inf_nan=False, strict=True,
                                  description="[m/s], from 5 mm/s (plans of minutes) to 1 m/s")
    max_tool_accel: float = Field(0.25, ge=0.005, le=10.0, allow_inf_nan=False, strict=True,
                                  description="[m/s^2]")
    approach_distance: float = Field(0.02, gt=0, le=0.1, allow_inf_nan=False, strict=True,
                                     description="approach and retreat length [m], at most 100 mm")


class Task(_Model):
    """A planning task (SI units: m, rad, s)."""

    format: Literal["tooltransfer.task/1"] = FORMAT
    name: str = Field(min_length=1, max_length=MAX_NAME,
                      description="names output files (plan_<name>.png): no '/', '\\' or control characters")
    description: str = Field("", max_length=MAX_TEXT)
    tool: Annotated[str, Field(max_length=MAX_NAME)] | InlineTool = Field(
        description="library tool name (tooltransfer tools) or an inline tool")
    object: ObjectSpec = ObjectSpec()
    start: Point
    target: Point
    obstacles: list[Obstacle] = Field([], max_length=32)
    safety_margin: float = Field(SAFETY_MARGIN, ge=0, le=0.1, allow_inf_nan=False, strict=True,
                                 description="delta of the paper's section IV.E [m]")
    platform: PlatformSpec = PlatformSpec()
    skills: SkillsSpec
    variants: Variants = Variants()
    oe: OEOptions = OEOptions()
    ss: SSOptions = SSOptions()
    timing: Timing = Timing()
    fixed_points: list[Point] | None = Field(None, max_length=64,
                                             description="manual override of the demonstrations' corners")
    _source: str | None = PrivateAttr(None)

    @property
    def source(self) -> str | None:
        """The file the task was read from (absolute; :func:`load_task`), or None for a task built in code:
        relative paths in the task (the skills' dataset or file) are relative to its folder."""
        return self._source

    @field_validator("name")
    @classmethod
    def _file_name(cls, v: str) -> str:
        if v.strip(".") == "" or any(c in "/\\" or ord(c) < 32 or ord(c) == 127 for c in v):
            raise ValueError("a name without '/', '\\' or control characters, not only dots (it names output files)")
        return v


def schema_default(model: type[BaseModel], name: str) -> Any:
    """The default of field ``name`` of the schema section ``model`` (e.g. ``OEOptions``, ``"n_samples"``):
    what the planner's own options types take as theirs, so that a default is written once."""
    return model.model_fields[name].default



def push_search_steps(n_faces: int, max_pushes: int, segments: int) -> int:
    """Work of the ``qp`` variant's push-sequence search
    (:func:`tooltransfer.planner.planning.oe.sequence_proxy.ranked_sequences`) in steps of equal cost (their
    time in ``benchmarks/README.md``): every face order of at most ``max_pushes`` pushes is enumerated
    (about 1/6 step each) and the ones without a face twice in a row split ``segments`` phases by
    dynamic programming (``pushes x segments`` steps each)."""
    f = n_faces
    enumerated = sum(f**p for p in range(1, max_pushes + 1))
    split = sum(f * (f - 1) ** (p - 1) * p * segments for p in range(1, min(max_pushes, segments) + 1))
    return split + enumerated // 6


def _loc(loc: tuple[int | str, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in ("disc", "polygon", "str", "float", "InlineTool") or part.startswith(
                ("function-", "tuple[", "constrained-")):
            continue  # pydantic's union-branch tags, not field names
        else:
            out += f".{part}" if out else str(part)
    return out or "<root>"


def task_from_dict(data: Any, source: str = "<dict>") -> Task:
    """Validate parsed task data; errors name ``source`` and the field path."""
    if not isinstance(data, dict):
        raise TaskFileError(source, "<root>", "a mapping of task fields", type(data).__name__)
    try:
        task = Task.model_validate(data)
    except ValidationError as exc:
        # the deepest error: for `tool: str | InlineTool`, the inline tool's field, not "a valid string"
        err = max(exc.errors(), key=lambda e: len(e["loc"]))
        got = err.get("input")
        got_txt = repr(got) if not isinstance(got, dict | list) else type(got).__name__
        raise TaskFileError(source, _loc(err["loc"]), err["msg"].removeprefix("Value error, "), got_txt) from None
    if np.hypot(task.target[0] - task.start[0], task.target[1] - task.start[1]) < 1e-6:
        raise TaskFileError(source, "target", "a point other than the start (a zero-length move)", task.target)
    _check_duration(task, source)
    if isinstance(task.tool, InlineTool):
        from tooltransfer.tools.library import tool_from_dict

        try:
            tool = tool_from_dict(json.loads(task.tool.model_dump_json(exclude_none=True)), source=f"{source}: tool",
                                  **_derive_options(task))
        except ToolSpecError as exc:
            raise TaskFileError(source, f"tool.{exc.field}", exc.reason) from None
    else:
        from tooltransfer.tools.library import library_names, load_tool

        if task.tool not in library_names():
            raise TaskFileError(source, "tool", f"a library tool ({', '.join(library_names())})", repr(task.tool))
        try:
            tool = load_tool(task.tool, **_derive_options(task))
        except ToolSpecError as exc:  # an outline-only library tool with no face for this object
            raise TaskFileError(source, "tool", exc.reason, repr(task.tool)) from None
    _check_search(task, len(tool.faces), source)
    return task


def _check_duration(task: Task, source: str) -> None:
    """Refuse timing limits under which the plan would last more than :data:`MAX_PLAN_DURATION`: the
    straight push from start to target with the approach and the retreat is a lower bound."""
    t = task.timing
    push = float(np.hypot(task.target[0] - task.start[0], task.target[1] - task.start[1]))
    least = min_jerk_time(push, t.max_tool_speed, t.max_tool_accel) + 2 * min_jerk_time(
        t.approach_distance, t.max_tool_speed, t.max_tool_accel)
    if least <= MAX_PLAN_DURATION:
        return
    by_speed = 1.875 * push / t.max_tool_speed >= np.sqrt(10.0 / np.sqrt(3.0) * push / t.max_tool_accel)
    field, value = ("max_tool_speed", t.max_tool_speed) if by_speed else ("max_tool_accel", t.max_tool_accel)
    raise TaskFileError(source, f"timing.{field}", f"limits under which the plan lasts at most {MAX_PLAN_DURATION:g} "
                        f"s ({int(MAX_PLAN_DURATION * PLAN_RATE)} samples at {PLAN_RATE:g} Hz; the straight push of "
                        f"{push:.3g} m from start to target with approach and retreat alone takes {least:.4g} s)",
                        value)


def _check_search(task: Task, n_faces: int, source: str) -> None:
    """Refuse a push-sequence search larger than :data:`MAX_SEARCH_STEPS` for a tool of ``n_faces``."""
    o = task.oe
    steps = push_search_steps(n_faces, o.max_pushes, o.segments)
    if steps > MAX_SEARCH_STEPS:
        raise TaskFileError(source, "oe.max_pushes", f"a push-sequence search of at most {MAX_SEARCH_STEPS} steps "
                            f"(face orders of at most max_pushes pushes of the tool's {n_faces} faces, split over "
                            f"oe.segments = {o.segments} phases; lower oe.max_pushes or oe.segments)",
                            f"{o.max_pushes} ({steps} steps)")


def load_task(path: str | Path) -> Task:
    """Read and validate a task file (YAML or JSON): ``path`` is a file (relative to the working folder)
    or, where no such file exists, the name of a bundled task (``"paper/transfer_tool2"``, with or
    without ``.yaml``; :mod:`tooltransfer.problems.named`), as the CLI takes them."""
    from tooltransfer.problems.named import bundled_tasks, task_file
    from tooltransfer.yaml_file import read_yaml

    path = task_file(path)
    if not path.exists():
        names = ", ".join(bundled_tasks())
        raise TaskFileError(str(path), "<file>", f"a readable task file or a bundled task name ({names})",
                            "no such file and no bundled task of that name")
    task = task_from_dict(read_yaml(path, TaskFileError, "task file"), str(path))
    task._source = str(Path(path).resolve())
    return task


def task_origin(task: Task, task_path: str | Path | None = None) -> str | Path:
    """Where relative paths in ``task`` start: ``task_path`` when given, else the file it was loaded from
    (:attr:`Task.source`), else the working folder."""
    if task_path is not None:
        return task_path
    return task.source if task.source is not None else "."


def task_tool(task: Task, friction: float | None = None) -> Tool:
    """The task's tool. A tool without faces gets the faces derived from its outline for the task's
    object radius, its platform and the tool-object friction ``friction`` (default the task's
    ``object.mechanics.mu``, else the platform's nominal 0.8)."""
    from tooltransfer.tools.library import load_tool, tool_from_dict

    options = _derive_options(task, friction)
    if isinstance(task.tool, InlineTool):
        return tool_from_dict(json.loads(task.tool.model_dump_json(exclude_none=True)), source="task tool", **options)
    return load_tool(task.tool, **options)


def faces_derived(task: Task) -> bool:
    """Whether the task's tool has no faces of its own (they are derived from its outline)."""
    if isinstance(task.tool, InlineTool):
        return task.tool.faces is None
    from tooltransfer.tools.library import library_has_faces

    return not library_has_faces(task.tool)


def _derive_options(task: Task, friction: float | None = None) -> dict[str, Any]:
    """What a tool without faces is derived for (:func:`task_tool`): ``object_radius``, ``friction`` and
    ``platform`` (the task's Omni for the tool's ``a_t``)."""
    if friction is None and task.object.mechanics is not None:
        friction = task.object.mechanics.mu
    return {"object_radius": task.object.radius, "friction": friction,
            "platform": lambda a_t: _omni(task, a_t)}


def task_platform(task: Task, tool: Tool) -> OmniPlatform:
    """The task's Omni carrying ``tool`` (its ``a_t``)."""
    return _omni(task, tool.a_t)


def _omni(task: Task, a_t: float) -> OmniPlatform:
    """The task's Omni with a tool of length ``a_t`` [m]."""
    from tooltransfer.tools.omni.platform import DEFAULT_LIMITS, JointLimits, OmniPlatform

    spec = task.platform
    limits = DEFAULT_LIMITS if spec.limits is None else JointLimits(spec.limits.lower, spec.limits.upper, "task file")
    return OmniPlatform(a_t=a_t, base_xy=spec.base_xy, base_yaw=spec.base_yaw,
                        table_height=spec.table_height, limits=limits)


def task_obstacles(task: Task) -> list[ObstacleShape]:
    """The task's obstacles as :class:`tooltransfer.tools.objects.Disc` and shapely polygons."""
    from tooltransfer.tools.objects import Disc

    return [
        Disc(np.array(o.centre), o.radius) if isinstance(o, DiscObstacle) else shapely.Polygon(o.vertices)
        for o in task.obstacles
    ]


def task_json_schema() -> str:
    """The JSON Schema of task files, as text."""
    return json.dumps(Task.model_json_schema(), indent=2)


def resolve(task_path: str | Path, relative: str) -> Path:
    """A path given in a task file, relative to that file's folder (absolute paths kept)."""
    p = Path(relative)
    return p if p.is_absolute() else Path(task_path).parent / p


__all__ = [
    "FORMAT",
    "MAPPING_K",
    "MAX_PLAN_DURATION",
    "MAX_SEARCH_STEPS",
    "SAFETY_MARGIN",
    "DiscObstacle",
    "OEOptions",
    "OEVariant",
    "PolygonObstacle",
    "SSOptions",
    "SSVariant",
    "Task",
    "TaskFileError",
    "UnknownToolError",
    "VirtualMotion",
    "faces_derived",
    "load_task",
    "min_jerk_time",
    "push_search_steps",
    "resolve",
    "schema_default",
    "task_from_dict",
    "task_json_schema",
    "task_obstacles",
    "task_platform",
    "task_tool",
]
