"""Batch files: a family of random tasks, as a pydantic schema (SI units: m, rad, s).

A batch file (YAML, format ``tooltransfer.batch/1``) says how many tasks, the seed, which tools,
where starts and targets may lie (inside the Omni's reach for the tool, shrunk or grown by a
margin, optionally inside a box), how far apart they are, how many obstacles of which size and
shape, which variants to run, the timeout and whether to simulate. Example::

    format: tooltransfer.batch/1
    name: small
    seed: 7
    count: 12
    tools: [slope, finger]
    dataset: ../data/finger_demos        # relative to the batch file
    start: {reach_margin: 0.015}
    target: {reach_margin: 0.005, box: {x: [-0.12, 0.12], y: [0.1, 0.25]}}
    distance: [0.04, 0.12]
    heading: [1.9, 3.1]                  # optional: direction from start to target [rad]
    obstacles: {count: [0, 3], radius: [0.003, 0.008], kinds: [disc, polygon]}
    variants: {oe: [qp, mapping], ss: [arch]}
    simulate: {enabled: false, seed: 0}       # execute solved plans open and closed loop
    timeout: 60
    task: {safety_margin: 0.005}         # extra task fields, the same in every task

With ``tools: choose`` (every library tool) or ``tools: {choose: [slope, finger]}`` every task is
given to :func:`tooltransfer.choose_tool` with those tools (one job per task and variant pair, the
choice's executions included, ``timeout`` for the whole choice): the row's tool is the chosen one
(``none`` when no tool solves the task) and ``batch report`` counts how often each tool is chosen.
The tools are still used in turn to place each task's start and target inside a tool's reach.

:func:`load_batch` reports errors with the file, the field path and what was expected.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from tooltransfer.problems.task import TaskFileError, _loc

FORMAT = "tooltransfer.batch/1"

# every number is bounded (the bounds are in ``tooltransfer batch schema``): coordinates within 10 m
# of the origin as in task files, lengths within a metre, times within an hour
Finite = Annotated[float, Field(ge=-10.0, le=10.0, allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, le=1.0, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(ge=0, le=1.0, allow_inf_nan=False)]
Seconds = Annotated[float, Field(gt=0, le=3600.0, allow_inf_nan=False)]
Seed = Annotated[int, Field(ge=0, le=2**63 - 1)]  # SQLite's integers


class BatchFileError(TaskFileError):
    """A batch file is unreadable or invalid; names the file, the field path and what was expected."""


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _ordered(v: tuple[Any, Any]) -> tuple[Any, Any]:
    if v[0] > v[1]:
        raise ValueError("a range [low, high] with low <= high")
    return v


Range = Annotated[tuple[Finite, Finite], AfterValidator(_ordered)]
PositiveRange = Annotated[tuple[Positive, Positive], AfterValidator(_ordered)]
Count = Annotated[int, Field(ge=0, le=20)]
Radius = Annotated[float, Field(gt=0, le=0.1, allow_inf_nan=False)]


class Box(_Model):
    """An axis-aligned box in the world frame [m]."""

    x: Range
    y: Range


class Region(_Model):
    """Where a start (or target) may lie: the tool's reach region shrunk by ``reach_margin`` (grown
    when negative, so that some points fall outside the reach), intersected with ``box``."""

    reach_margin: Annotated[float, Field(ge=-0.1, le=0.1, allow_inf_nan=False)] = Field(
        0.01, description="[m]; positive keeps points inside the reach boundary by that much")
    box: Box | None = None


class Obstacles(_Model):
    """Random obstacles near the straight way from start to target."""

    count: Annotated[tuple[Count, Count], AfterValidator(_ordered)] = (0, 2)
    radius: Annotated[tuple[Radius, Radius], AfterValidator(_ordered)] = Field(
        (0.003, 0.008), description="disc radius or polygon circumradius [m], at most 0.1")
    kinds: list[Literal["disc", "polygon"]] = Field(["disc"], min_length=1, max_length=8)
    spread: NonNegative = Field(0.02, description="largest sideways offset from the start-target line [m]")
    clearance: Annotated[float, Field(ge=0, le=0.1, allow_inf_nan=False)] = Field(
        0.004, description="kept between an obstacle and the object at start and target, on top of the safety "
        "margin [m]")


class VariantGrid(_Model):
    """Variants run on every task (their product)."""

    oe: list[Literal["qp", "mapping"]] = Field(["qp"], min_length=1, max_length=8)
    ss: list[Literal["arch", "dmp", "grid", "opt"]] = Field(["arch"], min_length=1, max_length=8)

    def pairs(self) -> list[tuple[str, str]]:
        """``(oe, ss)`` pairs, in a fixed order."""
        return [(o, s) for o in dict.fromkeys(self.oe) for s in dict.fromkeys(self.ss)]


class Simulation(_Model):
    """Executing solved plans on the simulated platform (MuJoCo): each one open loop (the planned
    joints tracked, :func:`tooltransfer.planner.execution.simulate.simulate_plan`) and closed loop (re-planning from the
    observed object, :func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`)."""

    enabled: bool = Field(False, description="execute solved plans (``batch run --simulate`` / ``--no-simulate`` "
                          "overrides it)")
    tolerance: Annotated[float, Field(gt=0, le=0.1, allow_inf_nan=False)] = Field(
        0.01, description="``sim_success``: the open-loop run ends with the object within this of the target [m] "
        "(the half side of the demonstrations' target square)")
    closed_loop_tolerance: Annotated[float, Field(gt=0, le=0.1, allow_inf_nan=False)] = Field(
        0.001, description="the closed loop stops once the object is measured within this of the target [m]")
    camera_noise: Annotated[float, Field(ge=0, le=0.05, allow_inf_nan=False)] = Field(
        0.0015, description="standard deviation of one camera frame per axis in the closed loop [m]")
    seed: Seed = Field(0, description="camera-noise seed: task i's closed loop uses a seed "
                       "drawn from [seed, i] (the same for every variant of the task)")
    timeout: Seconds = Field(120.0, description="per execution (open loop, closed loop) of a plan [s], at most 3600")

    def closed_loop_seed(self, index: int) -> int:
        """The closed loop's camera-noise seed of task ``index`` (deterministic, independent of ``count``)."""
        import numpy as np

        return int(np.random.SeedSequence([self.seed, index]).generate_state(1)[0])


class BatchSpec(_Model):
    """A batch of generated tasks."""

    format: Literal["tooltransfer.batch/1"] = FORMAT
    name: str = Field(min_length=1, max_length=80, pattern=r"^[A-Za-z0-9_.-]+$")
    description: str = Field("", max_length=4000)
    seed: Seed = 0
    count: Annotated[int, Field(ge=1, le=1_000_000)]
    tools: list[Annotated[str, Field(max_length=100)]] = Field(
        min_length=1, max_length=64, description="library tool names, used in turn; or 'choose' (every library "
        "tool) or {choose: [names]}: each task with the best of these tools (tooltransfer choose)")
    choose: bool = Field(False, description="each task with the best of ``tools`` (set by ``tools: choose``)")
    dataset: str = Field(min_length=1, max_length=4096,
                         description="demonstration dataset folder, relative to the batch file")
    start: Region = Region(reach_margin=0.015)
    target: Region = Region(reach_margin=0.005)
    distance: PositiveRange = Field((0.04, 0.12), description="start-target distance range [m]")
    heading: Annotated[tuple[Annotated[float, Field(ge=-7, le=7, allow_inf_nan=False)],
                             Annotated[float, Field(ge=-7, le=7, allow_inf_nan=False)]],
                       AfterValidator(_ordered)] | None = Field(
        None, description="range of the direction from start to target [rad] (world frame, from +x); "
        "none: any direction")
    obstacles: Obstacles = Obstacles()
    variants: VariantGrid = VariantGrid()
    simulate: Simulation = Simulation()
    timeout: Seconds = Field(60.0, description="per task and variant [s], at most 3600")
    task: dict[str, Any] = Field({}, description="extra task fields, the same in every task")

    @model_validator(mode="before")
    @classmethod
    def _choose_tools(cls, data: Any) -> Any:
        """``tools: choose`` and ``tools: {choose: [names]}`` as ``choose: true`` with the tools listed."""
        if not isinstance(data, dict):
            return data
        tools = data.get("tools")
        if tools == "choose":
            from tooltransfer.tools.library import library_names

            return {**data, "tools": list(library_names()), "choose": True}
        if isinstance(tools, dict) and set(tools) == {"choose"}:
            return {**data, "tools": tools["choose"], "choose": True}
        return data

    @field_validator("tools")
    @classmethod
    def _library(cls, v: list[str]) -> list[str]:
        from tooltransfer.tools.library import library_names

        names = library_names()
        bad = [t for t in v if t not in names]
        if bad:
            raise ValueError(f"library tool names ({', '.join(names)}), not {bad[0]!r}")
        return v

    @model_validator(mode="after")
    def _no_generated_fields(self) -> BatchSpec:
        owned = {"format", "name", "tool", "start", "target", "obstacles", "skills", "variants"}
        clash = sorted(owned & set(self.task))
        if clash:
            raise ValueError(f"task: fields the generator sets itself cannot be given ({', '.join(clash)})")
        return self

    def digest(self) -> str:
        """Hash of the batch's content without ``simulate.enabled`` (nor ``choose`` when false; a store
        refuses to resume a different batch; whether plans are executed is a setting of its own, checked by name:
        :func:`tooltransfer.planner.apps.batch.store_settings.open_batch_store`)."""
        data = self.model_dump(mode="json")
        data["simulate"].pop("enabled")
        if not data["choose"]:  # the digests of batches without a choice are those they had before it existed
            data.pop("choose")
        return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


def batch_from_dict(data: Any, source: str = "<dict>") -> BatchSpec:
    """Validate parsed batch data; errors name ``source`` and the field path."""
    if not isinstance(data, dict):
        raise BatchFileError(source, "<root>", "a mapping of batch fields", type(data).__name__)
    try:
        return BatchSpec.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        got = err.get("input")
        got_txt = repr(got) if not isinstance(got, dict | list) else type(got).__name__
        raise BatchFileError(source, _loc(err["loc"]), err["msg"].removeprefix("Value error, "), got_txt) from None


def load_batch(path: str | Path) -> BatchSpec:
    """Read and validate a batch file (YAML or JSON)."""
    from tooltransfer.yaml_file import read_yaml

    p = Path(path)
    spec = batch_from_dict(read_yaml(p, BatchFileError, "batch file"), str(p))
    folder = dataset_folder(spec, p)
    if not folder.is_dir():
        raise BatchFileError(str(p), "dataset", "a dataset folder (relative to the batch file)", str(folder))
    return spec


def dataset_folder(spec: BatchSpec, batch_path: str | Path) -> Path:
    """The batch's dataset folder, absolute."""
    d = Path(spec.dataset)
    return (d if d.is_absolute() else Path(batch_path).resolve().parent / d).resolve()


def batch_json_schema() -> str:
    """The JSON Schema of batch files, as text."""
    return json.dumps(BatchSpec.model_json_schema(), indent=2)
