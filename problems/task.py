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
from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
import shapely
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from dmp.errors import InputError
from tools.errors import ToolSpecError, UnknownToolError

if TYPE_CHECKING:
    from tools.model import Tool
    from tools.objects import Obstacle as ObstacleShape
    from tools.omni.platform import OmniPlatform

FORMAT = "tooltransfer.task/1"

# strict: a YAML true/false or a quoted number is a wrong type, not 1.0 / 0.0 (ints are still taken)
Finite = Annotated[float, Field(allow_inf_nan=False, strict=True)]
# bounded: 1e3 is far beyond any table-top quantity here (m, kg, m/s, m/s^2), huge values overflow downstream
Positive = Annotated[float, Field(gt=0, le=1e3, allow_inf_nan=False, strict=True)]
NonNegative = Annotated[float, Field(ge=0, le=1e3, allow_inf_nan=False, strict=True)]
# table-top coordinates: within 10 m of the origin (huge values overflow the geometry downstream)
Coordinate = Annotated[float, Field(ge=-10.0, le=10.0, allow_inf_nan=False, strict=True)]
Point = Annotated[tuple[Coordinate, Coordinate], Field(description="(x, y) in the world frame [m], |x|, |y| <= 10")]


class TaskFileError(InputError):
    """A task file is unreadable or invalid; names the file, the field path and what was expected."""

    def __init__(self, path: str, field: str, expected: str, got: object | None = None) -> None:
        self.path = path
        super().__init__(f"{path}: {field}", expected, got)


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class DiscObstacle(_Model):
    """A round obstacle."""

    kind: Literal["disc"] = "disc"
    centre: Point
    radius: Positive = Field(description="[m]")


class PolygonObstacle(_Model):
    """A convex polygonal obstacle."""

    kind: Literal["polygon"] = "polygon"
    vertices: list[Point] = Field(min_length=3, description="convex polygon, either orientation [m]")

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


class InlineFace(_Model):
    name: str
    segment: tuple[Point, Point]
    push_angle: Finite | str = Field(description="[rad] in the tool frame; numbers or 'pi' expressions")
    theta_b: Finite | str = Field(description="cone half-angle [rad], in (0, pi/2)")
    contact_range: tuple[NonNegative, NonNegative] | None = None


class InlineTool(_Model):
    """A tool defined in the task itself (same fields as the library's YAML files)."""

    name: str
    a_t: Positive = Field(description="tool length of Table I's tool row [m]")
    outline: list[Point] = Field(min_length=3, description="simple polygon in the tool frame [m]")
    faces: list[InlineFace] = Field(min_length=1)
    description: str = ""
    notes: str = ""


class MechanicsSpec(_Model):
    """The push model's parameters (DESIGN section 10), overriding the ones identified from the
    demonstrations (or the platform's nominal values when none were identified)."""

    mu: float = Field(gt=0, le=10, allow_inf_nan=False, strict=True,
                      description="Coulomb friction coefficient between the tool and the object")
    c: float = Field(gt=0, le=2, allow_inf_nan=False, strict=True,
                     description="limit-surface ratio m_max / (R f_max) of the object on the table "
                                 "(2/3 uniform pressure, 1 a rim)")


class ObjectSpec(_Model):
    """The pushed object: a disc (the paper's puck)."""

    radius: Positive = Field(0.0175, description="[m]")
    mass: Positive = Field(0.02, description="[kg], for the simulated platform")
    friction: Positive = Field(0.3, description="sliding friction coefficient against the table")
    mechanics: MechanicsSpec | None = Field(
        None, description="push model override (default: identified with the skills, else mu 0.8, c 0.59)")


class LimitsSpec(_Model):
    lower: tuple[Finite, Finite, Finite] = Field(description="(q1, q2, q3) [rad], Table I convention")
    upper: tuple[Finite, Finite, Finite] = Field(description="(q1, q2, q3) [rad]")


class PlatformSpec(_Model):
    """Placement of the Omni; omitted fields take the defaults of :class:`tools.omni.platform.OmniPlatform`."""

    base_xy: Point = (0.0, 0.0)
    base_yaw: Finite = Field(float(np.pi / 2), description="[rad]; pi/2 points q1 = 0 forward (+y)")
    table_height: Finite = Field(0.0, description="height of the pushing plane in the base frame [m]")
    limits: LimitsSpec | None = None


class SkillsSpec(_Model):
    """Where the skills come from: a demonstration dataset (learned and cached) or a skills file."""

    dataset: str | None = Field(None, description="dataset folder, relative to the task file")
    file: str | None = Field(None, description="saved skills file, relative to the task file")

    @model_validator(mode="after")
    def _one(self) -> SkillsSpec:
        if (self.dataset is None) == (self.file is None):
            raise ValueError("exactly one of 'dataset' and 'file'")
        return self


class Variants(_Model):
    oe: Literal["mapping", "qp"] = Field("qp", description="OE condensing: the paper's mapping or the QP search")
    ss: Literal["arch", "dmp", "opt"] = Field(
        "opt", description="switch paths: the CasADi NLP (default), DMP recombination (the paper) or the "
        "geometric arch (a reference)",
    )


class OEOptions(_Model):
    """Options of OE condensing (see :class:`planner.oe.QPOptions`)."""

    n_samples: int = Field(120, ge=10)
    n_basis: int = Field(25, ge=1)
    segments: int = Field(10, ge=1)
    max_pushes: int = Field(4, ge=1)
    candidates: int = Field(3, ge=1)
    switch_price: NonNegative = Field(2e-7, description="cost per face change [m^2]")
    k: float = Field(0.5, gt=0, lt=1, description="adjusting factor of the mappings (6)-(7)")
    tube: Positive = Field(0.01, description="tube radius around the universal path, mapping variant [m]")
    friction_cone_fraction: float = Field(
        0.5, gt=0, le=1, allow_inf_nan=False,
        description="share of the friction cone's half-angle atan(mu) the planned object directions may use")
    contact_margin: NonNegative = Field(
        0.0002, description="distance the contact keeps from the ends of a face's usable range [m]")
    contact_span: Positive = Field(
        0.012, description="longest stretch of a face the contact may use, about its middle [m] (the reach "
                           "is planned for the tool at both ends of it)")
    max_contacts: int = Field(6, ge=1, le=10, description="most contacts (re-contacts + 1) one push may use")
    self_consistency_tol: Positive = Field(
        1e-4, description="largest distance between the planned object path and the push model's replay "
                          "of the planned tool path for a solved plan [m]")


class SSOptions(_Model):
    """Options of the switch paths."""

    virtual_motion: Literal["arch", "line"] = "arch"
    n_knots: int = Field(40, ge=4)
    clearance: NonNegative = Field(
        0.002, description="tool-object and tool-obstacle clearance kept during switches [m]"
    )


class Timing(_Model):
    """Time scaling of the executed plan."""

    max_tool_speed: Positive = Field(0.05, description="[m/s]")
    max_tool_accel: Positive = Field(0.25, description="[m/s^2]")
    approach_distance: Positive = Field(0.02, description="approach and retreat length [m]")


class Task(_Model):
    """A planning task (SI units: m, rad, s)."""

    format: Literal["tooltransfer.task/1"] = FORMAT
    name: str = Field(min_length=1)
    description: str = ""
    tool: str | InlineTool = Field(description="library tool name (tooltransfer tools) or an inline tool")
    object: ObjectSpec = ObjectSpec()
    start: Point
    target: Point
    obstacles: list[Obstacle] = []
    safety_margin: NonNegative = Field(0.005, description="delta of the paper's section IV.E [m]")
    platform: PlatformSpec = PlatformSpec()
    skills: SkillsSpec
    variants: Variants = Variants()
    oe: OEOptions = OEOptions()
    ss: SSOptions = SSOptions()
    timing: Timing = Timing()
    fixed_points: list[Point] | None = Field(None, description="manual override of the demonstrations' corners")


def _loc(loc: tuple[int | str, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in ("disc", "polygon", "str", "float", "InlineTool") or part.startswith(("function-", "tuple[")):
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
    if isinstance(task.tool, InlineTool):
        from tools.library import tool_from_dict

        try:
            tool_from_dict(json.loads(task.tool.model_dump_json(exclude_none=True)), source=f"{source}: tool")
        except ToolSpecError as exc:
            raise TaskFileError(source, f"tool.{exc.field}", exc.reason) from None
    else:
        from tools.library import library_names

        if task.tool not in library_names():
            raise TaskFileError(source, "tool", f"a library tool ({', '.join(library_names())})", repr(task.tool))
    return task


def load_task(path: str | Path) -> Task:
    """Read and validate a task file (YAML or JSON)."""
    from problems.yaml_file import read_yaml

    return task_from_dict(read_yaml(path, TaskFileError, "task file"), str(path))


def task_tool(task: Task) -> Tool:
    """The task's tool."""
    from tools.library import load_tool, tool_from_dict

    if isinstance(task.tool, InlineTool):
        return tool_from_dict(json.loads(task.tool.model_dump_json(exclude_none=True)), source="task tool")
    return load_tool(task.tool)


def task_platform(task: Task, tool: Tool) -> OmniPlatform:
    """The task's Omni carrying ``tool`` (its ``a_t``)."""
    from tools.omni.platform import DEFAULT_LIMITS, JointLimits, OmniPlatform

    spec = task.platform
    limits = DEFAULT_LIMITS if spec.limits is None else JointLimits(spec.limits.lower, spec.limits.upper, "task file")
    return OmniPlatform(a_t=tool.a_t, base_xy=spec.base_xy, base_yaw=spec.base_yaw,
                        table_height=spec.table_height, limits=limits)


def task_obstacles(task: Task) -> list[ObstacleShape]:
    """The task's obstacles as :class:`tools.objects.Disc` and shapely polygons."""
    from tools.objects import Disc

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
    "DiscObstacle",
    "PolygonObstacle",
    "Task",
    "TaskFileError",
    "UnknownToolError",
    "load_task",
    "resolve",
    "task_from_dict",
    "task_json_schema",
    "task_obstacles",
    "task_platform",
    "task_tool",
]
