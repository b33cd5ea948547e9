"""Random tasks from a batch file, deterministic for its seed.

Task ``i`` is drawn from its own generator ``numpy.random.default_rng([seed, i])``, so it does not
depend on ``count`` or on which other tasks were drawn. Tools are used in turn (``i mod len``) so
each tool gets an equal share. Start and target are drawn uniformly inside the tool's reach region
(:func:`tooltransfer.tools.omni.reach.reachable_polygon` of the task's Omni with the tool's ``a_t``) shrunk by
the region's ``reach_margin`` and cut by its box, at a distance within ``distance``; obstacles
(discs or regular convex polygons) lie near the straight way between them, clear of the object at
start and target by the safety margin plus ``obstacles.clearance``. Each task is validated by
:func:`tooltransfer.problems.task.task_from_dict` before it is returned.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import shapely
import yaml

from tooltransfer.atomic import write_text
from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.spec import BatchSpec, Region, dataset_folder
from tooltransfer.problems.task import SAFETY_MARGIN, ObjectSpec, schema_default, task_from_dict

_TRIES = 2000


class GenerationError(InputError):
    """The batch's ranges leave no room for a task (e.g. an empty region or unreachable distances)."""

    def __init__(self, message: str) -> None:
        super().__init__("batch (start, target, distance, heading)", "ranges that leave room for a task", message)


@dataclass(frozen=True)
class GeneratedTask:
    """One generated task and the measures of its difficulty.

    Attributes:
        task_id: ``<batch name>-<index, 5 digits>``.
        index: position in the batch.
        tool: library tool name.
        data: the task's fields (as in a task file); ``skills.dataset`` is absolute.
        n_obstacles: obstacles placed (may be fewer than drawn when there was no room).
        start_reach, target_reach: signed distance [m] of the start and target to the reach boundary
            (positive inside).
        distance: start-target distance [m].
    """

    task_id: str
    index: int
    tool: str
    data: dict[str, Any] = field(repr=False)
    n_obstacles: int
    start_reach: float
    target_reach: float
    distance: float

    @property
    def reach_margin(self) -> float:
        """The smaller of the start's and the target's distance to the reach boundary [m]."""
        return min(self.start_reach, self.target_reach)


def _base(spec: BatchSpec, tool: str, dataset: str) -> dict[str, Any]:
    return {"format": "tooltransfer.task/1", "tool": tool, **spec.task, "skills": {"dataset": dataset}}


@cache
def _reach(tool: str, extra_json: str) -> shapely.Polygon:
    import json

    from tooltransfer.problems.task import task_platform, task_tool
    from tooltransfer.tools.omni.reach import reachable_polygon

    probe = task_from_dict({"name": "probe", "tool": tool, "start": [0.0, 0.15], "target": [0.01, 0.15],
                            "skills": {"dataset": "."}, **json.loads(extra_json)}, "batch.task")
    return reachable_polygon(task_platform(probe, task_tool(probe)))


def _region(reach: shapely.Polygon, r: Region) -> shapely.Geometry:
    area = reach.buffer(-r.reach_margin)
    if r.box is not None:
        area = area.intersection(shapely.box(r.box.x[0], r.box.y[0], r.box.x[1], r.box.y[1]))
    return area


def _signed(reach: shapely.Polygon, p: np.ndarray) -> float:
    pt = shapely.Point(p)
    d = float(reach.exterior.distance(pt))
    return d if reach.contains(pt) else -d


def _point_in(rng: np.random.Generator, area: shapely.Geometry, what: str, index: int) -> np.ndarray:
    if area.is_empty or area.area <= 0:
        raise GenerationError(f"task {index}: the {what} region (reach shrunk by its margin, cut by its box) is empty")
    x0, y0, x1, y1 = area.bounds
    for _ in range(_TRIES):
        p = rng.uniform((x0, y0), (x1, y1))
        if area.contains(shapely.Point(p)):
            return p
    raise GenerationError(f"task {index}: no {what} found in its region")  # pragma: no cover - area > 0


def _obstacles(rng: np.random.Generator, spec: BatchSpec, start: np.ndarray, target: np.ndarray,
               keep: float) -> list[dict[str, Any]]:
    o = spec.obstacles
    n = int(rng.integers(o.count[0], o.count[1] + 1))
    d = target - start
    normal = np.array([-d[1], d[0]]) / np.linalg.norm(d)
    out: list[dict[str, Any]] = []
    for _ in range(n):
        for _ in range(50):
            kind = o.kinds[int(rng.integers(len(o.kinds)))]
            r = float(rng.uniform(*o.radius))
            c = start + rng.uniform(0.15, 0.85) * d + rng.uniform(-o.spread, o.spread) * normal
            if min(np.linalg.norm(c - start), np.linalg.norm(c - target)) >= r + keep:
                break
        else:
            continue  # no room for this one
        if kind == "disc":
            out.append({"kind": "disc", "centre": [round(float(c[0]), 6), round(float(c[1]), 6)],
                        "radius": round(r, 6)})
        else:
            k = int(rng.integers(3, 7))
            a = rng.uniform(0, 2 * np.pi) + np.arange(k) * 2 * np.pi / k
            v = c + r * np.column_stack([np.cos(a), np.sin(a)])
            out.append({"kind": "polygon", "vertices": [[round(float(x), 6), round(float(y), 6)] for x, y in v]})
    return out


def generate_task(spec: BatchSpec, index: int, dataset: str) -> GeneratedTask:
    """Task ``index`` of the batch; ``dataset`` is written as the task's ``skills.dataset``."""
    import json

    rng = np.random.default_rng([spec.seed, index])
    tool = spec.tools[index % len(spec.tools)]
    extra = json.dumps({k: v for k, v in spec.task.items() if k == "platform"}, sort_keys=True)
    reach = _reach(tool, extra)
    start_area, target_area = _region(reach, spec.start), _region(reach, spec.target)
    lo, hi = spec.distance
    for _ in range(_TRIES):
        start = _point_in(rng, start_area, "start", index)
        ring = shapely.Point(start).buffer(hi).difference(shapely.Point(start).buffer(lo))
        if spec.heading is not None and spec.heading[1] - spec.heading[0] < 2 * np.pi:
            a = np.linspace(spec.heading[0], spec.heading[1], 64)
            fan = np.vstack([start, start + 2 * hi * np.column_stack([np.cos(a), np.sin(a)])])
            ring = ring.intersection(shapely.Polygon(fan))
        area = target_area.intersection(ring)
        if area.area > 1e-8:
            target = _point_in(rng, area, "target", index)
            break
    else:
        raise GenerationError(f"task {index}: no target at a distance in [{lo}, {hi}] m (and within the heading "
                              "range) of any start")
    radius = float(spec.task.get("object", {}).get("radius", schema_default(ObjectSpec, "radius")))
    keep = radius + float(spec.task.get("safety_margin", SAFETY_MARGIN)) + spec.obstacles.clearance
    obstacles = _obstacles(rng, spec, start, target, keep)
    task_id = f"{spec.name}-{index:05d}"
    data = _base(spec, tool, dataset)
    data.update({"name": task_id, "description": f"generated: batch {spec.name}, seed {spec.seed}, task {index}",
                 "start": [round(float(v), 6) for v in start], "target": [round(float(v), 6) for v in target],
                 "obstacles": obstacles})
    task_from_dict(data, f"generated task {task_id}")
    return GeneratedTask(task_id, index, tool, data, len(obstacles), _signed(reach, np.array(data["start"])),
                         _signed(reach, np.array(data["target"])),
                         float(np.hypot(*(np.array(data["target"]) - np.array(data["start"])))))


def generate_tasks(spec: BatchSpec, batch_path: str | Path) -> list[GeneratedTask]:
    """Every task of the batch, with the dataset given as an absolute path."""
    dataset = str(dataset_folder(spec, batch_path))
    return [generate_task(spec, i, dataset) for i in range(spec.count)]


def write_tasks(spec: BatchSpec, batch_path: str | Path, out: str | Path) -> list[Path]:
    """Write every task of the batch as a task file ``<out>/<task id>.yaml``; the dataset is given
    relative to ``out`` so the folder can be moved with the repository. Returns the paths."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    rel = os.path.relpath(dataset_folder(spec, batch_path), folder.resolve())
    paths = []
    for i in range(spec.count):
        g = generate_task(spec, i, rel)
        p = folder / f"{g.task_id}.yaml"
        head = (f"# generated by `tooltransfer batch generate` from {Path(batch_path).name} (task {i});\n"
                f"# difficulty: {g.n_obstacles} obstacles, start {1e3 * g.start_reach:.1f} mm and target "
                f"{1e3 * g.target_reach:.1f} mm inside the reach boundary, {1e3 * g.distance:.1f} mm apart\n")
        write_text(p, head + yaml.safe_dump(g.data, sort_keys=False, default_flow_style=None))  # never half a task
        paths.append(p)
    return paths
