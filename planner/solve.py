"""The planner end to end: a task in, a plan out (``planner.solve``).

Stages (each timed in the plan's metrics): skills (the universal OE skill learned from the task's
dataset, cached in memory by the dataset's content hash), OE condensing with the chosen variant,
a switch between consecutive pushes, approach and retreat, timing under the tool's speed and
acceleration limits, inverse kinematics of the whole tool path (joint limits checked), and the
checks: the shared OE metrics on the dense object path, the switches' clearances, the joint-limit
violation.

Switch variants: ``arch`` (the geometric reference of :mod:`tools.arch`) is available; ``dmp`` and
``opt`` (the SS skill) are not yet and are refused with a clear error.
"""

from __future__ import annotations

import hashlib
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from dmp.errors import InputError
from planner.assemble import SwitchFailed, SwitchPath, assemble
from planner.oe.face_frame import FaceFrame
from planner.oe.generalize import generalize
from planner.oe.learn import OESkill, learn_oe_skill
from planner.oe.mapping_variant import MappingOptions, condense_mapping
from planner.oe.qp_variant import QPOptions, condense_qp
from planner.plan import Plan, Segment
from problems.task import Task, resolve, task_obstacles, task_platform, task_tool
from tools.arch import NoArch, swept_clearance, switch_path
from tools.library import load_tool
from tools.objects import Disc
from tools.omni.dh import D1, D_TOOL, L1, L2, THETA_TOOL

_SKILLS: dict[str, OESkill] = {}


def dataset_hash(folder: Path) -> str:
    """Content hash of a dataset folder (every file's name and bytes)."""
    h = hashlib.sha256()
    for p in sorted(folder.iterdir()):
        if p.is_file():
            h.update(p.name.encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def cache_dir() -> Path:
    """Where learned skills are kept between runs: ``$TOOLTRANSFER_CACHE`` or ``~/.cache/tooltransfer``."""
    return Path(os.environ.get("TOOLTRANSFER_CACHE", Path.home() / ".cache" / "tooltransfer"))


def oe_skill_from_dataset(folder: Path, k: float) -> OESkill:
    """The universal OE skill learned from a dataset, cached by the dataset's content hash and ``k``
    in memory and as a skill file in :func:`cache_dir` (a damaged cache file is relearned)."""
    from dmp.errors import SkillFileError

    key = f"{dataset_hash(folder)}:{k}"
    cached = cache_dir() / f"oe-{key.replace(':', '-k')}.json"
    if key not in _SKILLS and cached.is_file():
        try:
            _SKILLS[key] = OESkill.load(cached)
        except SkillFileError:
            cached.unlink(missing_ok=True)
    if key not in _SKILLS:
        from planner.segmentation import segment  # scipy.signal: half a second of imports, only to learn
        from problems.dataset import load_dataset

        ds = load_dataset(folder)
        tool = load_tool(ds.meta.tool) if not (folder / ds.meta.tool).is_file() else load_tool(folder / ds.meta.tool)
        demos, fixed = [], []
        for d in ds.demonstrations:
            pushes = segment(d, tool).demo_pushes(d)
            demos.append(pushes)
            fixed.append([i for i in range(len(pushes) - 1) if pushes[i].face != pushes[i + 1].face])
        _SKILLS[key] = learn_oe_skill(demos, tool, k=k, fixed=fixed)
        try:
            cached.parent.mkdir(parents=True, exist_ok=True)
            _SKILLS[key].save(cached)
        except OSError:
            pass  # a read-only home: the skill is relearned next time
    return _SKILLS[key]


def _describe(task: Task, tool: Any, platform: Any, obstacles: list) -> dict[str, Any]:
    from tools.objects import Disc

    return {
        "platform": {
            "dh": [
                {"joint": 1, "alpha": -np.pi / 2, "a": 0.0, "d": D1, "theta": "q1"},
                {"joint": 2, "alpha": 0.0, "a": L1, "d": 0.0, "theta": "q2"},
                {"joint": 3, "alpha": 0.0, "a": L2, "d": 0.0, "theta": "q3"},
                {"joint": "tool", "alpha": 0.0, "a": platform.a_t, "d": D_TOOL, "theta": THETA_TOOL},
            ],
            "base_xy": list(platform.base_xy), "base_yaw": platform.base_yaw,
            "table_height": platform.table_height, "a_t": platform.a_t,
            "joint_limits": {"lower": list(platform.limits.lower), "upper": list(platform.limits.upper)},
        },
        "object": {"radius": task.object.radius, "start": list(task.start), "goal": list(task.target)},
        "tool": {
            "name": tool.name, "outline": np.asarray(tool.outline.exterior.coords)[:-1].tolist(),
            "faces": [{"name": f.name, "segment": [f.start.tolist(), f.end.tolist()], "push_angle": f.push_angle,
                       "theta_b": f.theta_b} for f in tool.faces],
        },
        "obstacles": [
            {"kind": "disc", "centre": o.centre.tolist(), "radius": o.radius} if isinstance(o, Disc)
            else {"kind": "polygon", "vertices": np.asarray(o.exterior.coords)[:-1].tolist()} for o in obstacles
        ],
    }


def solve(task: Task, task_path: str | Path = ".") -> Plan:
    """Plan ``task`` (relative paths in it are relative to ``task_path``'s folder)."""
    stages: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(name: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        stages[f"time_{name}"] = now - clock
        clock = now

    if task.variants.ss != "arch":
        raise InputError("variants.ss", "'arch' (the SS skill variants 'dmp' and 'opt' are not available yet)",
                         task.variants.ss)
    tool = task_tool(task)
    platform = task_platform(task, tool)
    obstacles = task_obstacles(task)
    desc = _describe(task, tool, platform, obstacles)
    base = {"variant": {"oe": task.variants.oe, "ss": task.variants.ss}, "task": task.model_dump(mode="json"),
            **desc}
    if task.skills.dataset is None:
        raise InputError("skills.file", "a dataset (saved skills files are not supported yet)", task.skills.file)
    folder = resolve(task_path, task.skills.dataset)
    if not folder.is_dir():
        raise InputError("skills.dataset", "a dataset folder", str(folder))
    skill = oe_skill_from_dataset(folder, task.oe.k)
    lap("skills")
    t, x, _ = generalize(skill.dmp, np.array(task.start), np.array(task.target))
    target = np.array(task.target)
    if task.variants.oe == "qp":
        o = task.oe
        opts = QPOptions(n_samples=o.n_samples, n_basis=o.n_basis, segments=o.segments, max_pushes=o.max_pushes,
                         candidates=o.candidates, switch_price=o.switch_price, margin=task.safety_margin)
        push_plan = condense_qp(t, x, tool, platform, target, obstacles, opts)
    else:
        push_plan = condense_mapping(t, x, tool, platform, target, obstacles,
                                     MappingOptions(k=task.oe.k, tube=task.oe.tube, margin=task.safety_margin))
    lap("oe")
    if push_plan.status != "solved":
        return Plan(status="infeasible", reason=push_plan.reason, metrics=stages, **base)
    frames = {f: FaceFrame.build(tool, f, platform) for f in tool.face_names}
    clear = task.ss.clearance
    # the arch avoids disc obstacles; a polygon is taken as its enclosing disc (centroid, farthest vertex)
    discs = [o if isinstance(o, Disc) else _enclosing_disc(o) for o in obstacles]

    def arch(obj: np.ndarray, face_a: str, pose_a: np.ndarray, face_b: str, pose_b: np.ndarray) -> SwitchPath:
        da = pose_a[2] + tool.face(face_a).push_angle
        db = pose_b[2] + tool.face(face_b).push_angle
        try:
            xy = switch_path(tool, platform, obj, pose_a, da, pose_b, db, clearance=clear, obstacles=discs)
        except NoArch as exc:
            return SwitchPath(np.zeros((0, 2)), "infeasible", str(exc))
        dense = _densify(xy, 0.0005)
        near = min((swept_clearance(tool, platform, dense, o.centre, o.radius) for o in discs), default=np.inf)
        return SwitchPath(xy, min_clearance=swept_clearance(tool, platform, dense[8:-8], obj, task.object.radius),
                          info={"obstacle_clearance": float(near)})

    try:
        motion = assemble(push_plan, frames, platform, arch, v_max=task.timing.max_tool_speed,
                          a_max=task.timing.max_tool_accel, approach_distance=task.timing.approach_distance)
    except SwitchFailed as exc:
        return Plan(status="infeasible", reason=str(exc), metrics={**push_plan.metrics, **stages}, **base)
    lap("switches_and_timing")
    metrics = {**push_plan.metrics, **stages}
    metrics["switch_clearance_min"] = min((sw.min_clearance for *_, sw in motion.switches), default=float("inf"))
    metrics["switch_obstacle_clearance_min"] = min(
        (sw.info.get("obstacle_clearance", np.inf) for *_, sw in motion.switches), default=float("inf"))
    metrics["joint_limit_violation_max"] = float(motion.joint_violation.max())
    metrics["duration"] = float(motion.t[-1])
    metrics["stretch"] = motion.stretch
    if not np.isfinite(metrics["joint_limit_violation_max"]) or metrics["joint_limit_violation_max"] > 1e-9:
        bad = int(np.argmax(motion.joint_violation))
        return Plan(status="infeasible", metrics=metrics, **base,
                    reason=f"joint limits: the tool path leaves the Omni's limits at t = {motion.t[bad]:.2f} s "
                           f"by {motion.joint_violation[bad]:.3g} rad")
    pushes = tuple(Segment("push", a, b, (f,), {"direction": d}) for f, a, b, d in motion.pushes)
    switches = tuple(Segment("switch", a, b, (fa, fb), {"min_clearance": sw.min_clearance})
                     for fa, fb, a, b, sw in motion.switches)
    return Plan(status="solved", t=motion.t, object_xy=motion.object_xy, tool_pose=motion.tool_pose,
                joints=motion.joints, phase=motion.phase, face=motion.face, pushes=pushes, switches=switches,
                metrics=metrics, **base)


def _enclosing_disc(poly: Any) -> Any:
    from tools.objects import Disc

    ring = np.asarray(poly.exterior.coords)[:-1]
    c = ring.mean(axis=0)
    return Disc(c, float(np.linalg.norm(ring - c, axis=1).max()))


def _densify(xy: np.ndarray, step: float) -> np.ndarray:
    seg = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(2, int(np.ceil(s[-1] / step)) + 1)
    u = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(u, s, xy[:, j]) for j in range(2)])
