"""Closed-loop execution of a plan on the simulated platform (beyond the paper, which ran open loop).

What the platform shows (measured, ``tools.sim``): a round puck pushed by a flat face moves close to
the face's normal whatever the tool's direction inside the cone (tool 2's inclined face, tool moving
-30..30 degrees off the normal: the puck goes 2..15 degrees off it), and the normal turns with the
heading the Omni imposes (q1). The plan's pushes at the edge of the cone therefore drift: open loop,
the transfer plan ends about 30 mm from the target. Steering happens through *where* the faces
change, so the loop re-plans the corners from the observed puck:

1. the approach, as planned;
2. every push but the last two: re-anchored at the observed puck (the planned object path of the push
   translated to start there), the tool at the face's contact poses along it;
3. the last two faces ``f1``, ``f2``, in rounds. The puck is observed as the camera gives it (noisy,
   averaged over a few frames of the resting puck). The remaining displacement is split along the
   two faces' expected push directions (``r = a u1 + b u2``; a direction is the face's normal at
   the heading there plus a bias learned online from the puck's motion in earlier straight pushes
   of that face), and each face pushes its share in chunks of at most ``chunk`` [m], observed and
   split again after each chunk. The last chunk of a share stops short (``undershoot``): these
   faces cannot pull the puck back. The first round aims ``stage`` short of the target along the
   middle of the two directions, so that what is left lies inside the span of the two pushes; when
   the straight corner would hit an obstacle, or the directions cannot split the way there, ``f1``
   follows its planned push instead (re-anchored). Later rounds push only what brings the puck
   closer; the loop ends when the puck is measured within ``tolerance``, when no push of the pair
   can bring it closer, or after ``max_rounds``;
4. between faces, the plan's switch variant at the observed puck (the geometric arch when that
   fails); a re-contact with the same face backs off 3 mm, slides and approaches; a re-anchored
   push that would leave the Omni's reach is cut where it does.

Measured on the paper's transfer task (qp/opt plan, 10 camera-noise seeds): open loop 30 mm, closed
loop median 0.7 mm, at most 1.3 mm, 5-8 pushes and 2-6 switches.

Every move is tracked by the platform's PD loop (:meth:`tools.sim.SimPlatform.execute_tool_path`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from dmp.errors import InputError
from planner.assemble import SwitchPath
from planner.oe.face_frame import FaceFrame
from planner.plan import Plan
from planner.timing import min_jerk_along, min_jerk_duration
from problems.task import Task, task_from_dict, task_obstacles, task_platform, task_tool
from tools.objects import Disc
from tools.omni.ik import joint_path
from tools.sim import Execution, SimPlatform

BACK_OFF = 0.003
"""Distance [m] the tool backs off from the puck to re-contact it with the same face."""


@dataclass(frozen=True)
class ClosedLoopReport:
    """Outcome of a closed-loop execution.

    Attributes:
        status: ``"reached"`` (the measured puck within ``tolerance``; the true error can be larger by
            the camera's noise), ``"closest"`` (the last pair of faces cannot
            bring the puck closer: their observed directions do not span the rest), ``"rounds"``
            (``max_rounds`` used up) or ``"failed"`` (no admissible switch; ``reason`` says why).
        final_error: object centre to target at the end [m].
        n_pushes: pushes (chunks) executed; n_switches: face changes.
        bias: learned offset [rad] of the puck's direction from each face's normal.
        errors: object-to-target distance [m] after each push.
        wall_time: [s]; execution: the whole recording.
    """

    status: str
    reason: str
    final_error: float
    n_pushes: int
    n_switches: int
    bias: dict[str, float]
    errors: list[float]
    wall_time: float
    execution: Execution
    log: list[str] = field(default_factory=list)


class _Loop:
    """State of one closed-loop run."""

    def __init__(self, plan: Plan, task: Task, noise: float, frames: int, seed: int) -> None:
        from planner.solve import task_skills
        from planner.switches import arch_planner, skill_planner

        self.plan, self.task = plan, task
        self.tool = task_tool(task)
        self.platform = task_platform(task, self.tool)
        self.obstacles = task_obstacles(task)
        self.sim = SimPlatform(self.tool, self.platform, self.obstacles)
        from planner.solve import effective_margin, task_scene

        self.scene = task_scene(task, self.obstacles, effective_margin(task, self.obstacles))
        self.frames = {f: FaceFrame.build(self.tool, f, self.platform, self.scene) for f in self.tool.face_names}
        self.bias = dict.fromkeys(self.tool.face_names, 0.0)
        self.parts: list[Execution] = []
        self.log: list[str] = []
        self.errors: list[float] = []
        self.n_pushes = self.n_switches = 0
        self.v, self.a = task.timing.max_tool_speed, task.timing.max_tool_accel
        r, clear = task.object.radius, task.ss.clearance
        self.arch = arch_planner(self.tool, self.platform, r, self.obstacles, clear)
        self.switch = self.arch
        if plan.variant.get("ss") in ("dmp", "opt"):
            ss = task_skills(task).ss
            if ss is not None:
                self.switch = skill_planner(plan.variant["ss"], ss, self.tool, self.platform, r, self.obstacles,
                                            clear, task.ss.n_knots)
        self.face: str | None = None
        self.noise, self.n_frames, self.rng = noise, frames, np.random.default_rng(seed)
        from planner.solve import effective_margin

        self.margin = effective_margin(task, self.obstacles)
        self.obstacle_shapes = [ob.polygon() if isinstance(ob, Disc) else ob for ob in self.obstacles]
        self.seen: dict[str, int] = {}

    def observe(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The puck as the camera measures it while it rests (the mean of ``frames`` noisy frames)
        and the tool pose from the encoders."""
        o, pose = self.sim.observe()
        return o + self.rng.normal(0.0, self.noise / np.sqrt(self.n_frames), 2), pose

    def move(self, xy: NDArray[np.float64]) -> None:
        """Track the polyline ``xy`` (K, 2) [m] with a minimum-jerk profile within the limits."""
        length = float(np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1)))
        if length < 1e-5:
            return
        dur = min_jerk_duration(length, self.v, self.a)
        n = max(3, int(np.ceil(dur / 0.01)) + 1)
        t, path = min_jerk_along(xy, dur, n)
        self.parts.append(self.sim.execute_tool_path(t, path))

    def direction(self, face: str, o: NDArray[np.float64]) -> float:
        """The puck's expected world direction [rad] pushed by ``face`` at ``o``: normal + bias."""
        return float(self.frames[face].push_direction(o[None])[0]) + self.bias[face]

    def unit(self, face: str, o: NDArray[np.float64]) -> NDArray[np.float64]:
        """Unit vector (2,) of :meth:`direction`."""
        return _heading_unit(self.direction(face, o))

    def contact(self, face: str) -> str | None:
        """Bring ``face`` into contact with the observed puck; the reason when impossible."""
        o, pose = self.observe()
        target = self.frames[face].tool_pose(o[None])[0]
        if self.face == face:
            if np.hypot(*(target[:2] - pose[:2])) < 5e-4:
                return None
            u_a, u_b = (_heading_unit(p[2] + self.tool.face(face).push_angle) for p in (pose, target))
            self.move(np.vstack([pose[:2], pose[:2] - BACK_OFF * u_a, target[:2] - BACK_OFF * u_b, target[:2]]))
            return None
        assert self.face is not None  # the approach put a face in contact
        here = self.frames[self.face].tool_pose(o[None])[0]
        sw: SwitchPath = self.switch(o, self.face, here, face, target)
        if sw.status != "solved":
            self.log.append(f"switch {self.face} -> {face} at {np.round(o, 4).tolist()}: {sw.reason}; trying the arch")
            sw = self.arch(o, self.face, pose, face, target)
            if sw.status != "solved":
                return f"no switch {self.face} -> {face} at {np.round(o, 4).tolist()} m: {sw.reason}"
        self.move(np.vstack([pose[:2], sw.xy]))
        self.face = face
        self.n_switches += 1
        return None

    def push(self, face: str, path_from: Callable[[NDArray[np.float64]], NDArray[np.float64]],
             learn: bool = True) -> str | None:
        """Bring ``face`` into contact, then push the puck along the object path ``path_from(o)``
        (K, 2) [m] from the observed puck ``o`` (the tool at the face's contact poses), and learn the
        face's bias from where the puck went (when ``learn``: pushes along the expected direction;
        the puck's offset depends on the tool's, so planned pushes at the cone's edge would mislead).
        Returns the reason when no contact or push is possible."""
        why = self.contact(face)
        if why:
            return why
        before, pose = self.observe()
        path = path_from(before)
        tool = self.frames[face].tool_pose(path)
        out = np.flatnonzero(joint_path(self.platform, tool[:, :2]).violation > 0)
        if out.size:  # a re-anchored path can leave the reach: push as far as the Omni reaches
            if out[0] < 2:
                return f"push {face} from {np.round(before, 4).tolist()} m leaves the Omni's reach at once"
            tool, path = tool[: out[0]], path[: out[0]]
            self.log.append(f"push {face} cut at the Omni's reach after {len(path)} samples")
        try:
            self.move(np.vstack([pose[:2], tool[:, :2]]))
        except InputError as exc:  # the push would leave the Omni's reach
            return f"push {face} from {np.round(before, 4).tolist()} m: {exc}"
        after = self.observe()[0]
        self.n_pushes += 1
        moved = after - before
        planned = path[-1] - path[0]
        if learn and np.hypot(*moved) > 2e-3:
            # the puck's direction off the face's normal (at the middle of its move): the face's bias
            normal = float(self.frames[face].push_direction((0.5 * (before + after))[None])[0])
            off = float((np.arctan2(moved[1], moved[0]) - normal + np.pi) % (2 * np.pi) - np.pi)
            n = self.seen[face] = self.seen.get(face, 0) + 1
            self.bias[face] += (off - self.bias[face]) * max(0.5, 1.0 / n)
        err = float(np.hypot(*(np.array(self.task.target) - self.sim.observe()[0])))  # the true error
        self.errors.append(err)
        self.log.append(f"push {face}: planned {1e3 * np.hypot(*planned):.1f} mm, moved {1e3 * np.hypot(*moved):.1f} "
                        f"mm, bias {np.degrees(self.bias[face]):.1f} deg, error {1e3 * err:.1f} mm")
        return None


def execute_closed_loop(plan: Plan, *, chunk: float = 0.015, tolerance: float = 0.001, max_rounds: int = 6,
                        undershoot: float = 0.85, stage: float = 0.008,
                        camera_noise: float = 0.0015, frames: int = 10, seed: int = 0) -> ClosedLoopReport:
    """Execute a solved plan closed loop (module docstring) on the simulated platform.

    Args:
        plan: a solved plan (its task names the skills by absolute path, as :func:`planner.solve`
            writes it).
        chunk: longest push [m] of the last two faces before the puck is observed again.
        tolerance: the puck counts as at the target within this distance [m].
        max_rounds: how often the last pair of faces may be repeated.
        stage: the first round aims this far [m] short of the target along the middle of the last two
            faces' directions (the later rounds then start inside the span of their pushes).
        undershoot: share of the remaining push a face's last chunk makes (below 1: the faces cannot
            pull the puck back, so the loop approaches the target from short of it).
        camera_noise: standard deviation [m] per axis of one camera frame of the puck (the dataset's
            depth camera: 1.5 mm); the loop averages ``frames`` frames of the resting puck (noise
            drawn from ``numpy.random.default_rng(seed)``). The reported errors are the true ones.
    """
    if plan.status != "solved":
        raise InputError("plan", "a solved plan", plan.status)
    start = time.perf_counter()
    task = task_from_dict(plan.task, "plan.task")
    loop = _Loop(plan, task, camera_noise, frames, seed)
    target = np.array(task.target)
    loop.sim.reset(np.array(task.start), q0=plan.joints[0])
    approach = np.array([p == "approach" for p in plan.phase])
    loop.parts.append(loop.sim.execute(plan.t[approach], plan.joints[approach]))
    faces = [p.faces[0] for p in plan.pushes]
    loop.face = faces[0]
    status, reason = "rounds", ""
    # every push but the last two: the planned object path, re-anchored at the observed puck
    for seg in plan.pushes[:-2]:
        m = (plan.t >= seg.t_start) & (plan.t <= seg.t_end)
        planned = plan.object_xy[m]
        why = loop.push(seg.faces[0], lambda o, p=planned: p + (o - p[0]), learn=False)
        if why:
            status, reason = "failed", why
            break
    pair = faces[-2:] if len(faces) >= 2 else faces[-1:]

    def planned_xy(i: int) -> NDArray[np.float64]:
        seg = plan.pushes[i]
        return plan.object_xy[(plan.t >= seg.t_start) & (plan.t <= seg.t_end)]

    rounds = 0
    while status != "failed" and rounds < max_rounds:
        o = loop.observe()[0]
        if np.hypot(*(target - o)) <= tolerance:
            status = "reached"
            break
        if _pair_plan(loop, pair, o, target)[1] > np.hypot(*(target - o)) - 5e-4:
            status = "closest"
            reason = (f"the faces {' and '.join(pair)} cannot bring the puck closer than "
                      f"{1e3 * np.hypot(*(target - o)):.1f} mm (their observed push directions)")
            break
        rounds += 1
        # the first round pushes both faces as planned, aiming ``stage`` short of the target along the
        # middle of the two faces' directions, so the rest lies inside the span of the faces' pushes
        # whatever the first round's errors; later rounds only what brings the puck closer
        todo = list(pair) if rounds == 1 else _pair_plan(loop, pair, o, target)[0]
        aim = target
        if rounds == 1 and len(pair) == 2:
            mid = sum(loop.unit(f, o) for f in pair)
            aim = target - stage * mid / np.linalg.norm(mid)
        if rounds == 1 and len(pair) == 2 and _share(loop, todo, 0, o, aim) <= 2e-4:
            # the faces' expected directions do not split the way to the aim from here: when the last
            # face alone gets close, it pushes alone; else (the plan pushes at the cone's edge) the
            # first face follows its planned push, re-anchored at the puck
            u = loop.unit(pair[1], o)
            r = aim - o
            alone = o + max(0.0, r @ u) * u
            if np.hypot(*(aim - alone)) > 0.3 * np.hypot(*r) or _hits(loop, [o, alone]):
                prev = planned_xy(-2)
                why = loop.push(pair[0], lambda o, p=prev: p + (o - p[0]), learn=False)
                if why:
                    status, reason = "failed", why
                    break
            todo = [pair[1]]
        for k, face in enumerate(todo):
            o = loop.observe()[0]
            left = _share(loop, todo, k, o, aim)
            while left > 2e-4:
                # the last chunk stops short (``undershoot``): a puck pushed too far cannot be pushed
                # back by these faces, one not far enough is pushed on in the next round
                step = chunk if left > chunk else undershoot * left
                if k == 0 and len(todo) == 2 and rounds == 1 and _blocked(loop, todo, o, aim):
                    # the straight corner would take the puck into an obstacle: follow the plan's path
                    # of this push (re-anchored at the puck) for one more chunk
                    prev = planned_xy(-2)
                    why = loop.push(face, lambda o, p=prev: _along(p, o, chunk), learn=False)
                else:
                    why = loop.push(face, lambda o, f=face, step=step: _straight(loop, f, o, step))
                if why:
                    status, reason = "failed", why
                    break
                o = loop.observe()[0]
                left = _share(loop, todo, k, o, aim)
                if step < chunk:
                    break
            if status == "failed":
                break
    ex = Execution.concat(loop.parts)
    err = float(np.hypot(*(target - loop.sim.observe()[0])))
    if err <= tolerance:
        status, reason = "reached", ""
    return ClosedLoopReport(status, reason, err, loop.n_pushes, loop.n_switches, dict(loop.bias), loop.errors,
                            time.perf_counter() - start, ex, loop.log)


def _heading_unit(angle: float) -> NDArray[np.float64]:
    return np.array([np.cos(angle), np.sin(angle)])


def _straight(loop: _Loop, face: str, o: NDArray[np.float64], length: float) -> NDArray[np.float64]:
    """Object path (K, 2) [m]: ``length`` from ``o`` along the face's expected direction."""
    s = np.linspace(0.0, length, max(3, int(length / 5e-4)))
    return o + s[:, None] * loop.unit(face, o)


def _blocked(loop: _Loop, pair: list[str], o: NDArray[np.float64], target: NDArray[np.float64]) -> bool:
    """Whether the two straight pushes of ``pair`` from ``o`` to ``target`` (corner where the
    expected directions meet) bring the puck within the safety margin of an obstacle."""
    u = [loop.unit(f, o) for f in pair]
    a = np.column_stack(u)
    if abs(np.linalg.det(a)) < 1e-6:
        return False
    coef = np.maximum(np.linalg.solve(a, target - o), 0.0)
    return _hits(loop, [o, o + coef[0] * u[0], target])


def _hits(loop: _Loop, points: list[NDArray[np.float64]]) -> bool:
    """Whether the puck moved along the polyline ``points`` [m] comes within the safety margin of an
    obstacle (away from where it is now: it may start close, e.g. touching)."""
    import shapely

    if not loop.obstacles:
        return False
    grow = loop.task.object.radius + loop.margin
    swept = shapely.LineString(points).buffer(grow)
    near = shapely.Point(points[0]).buffer(grow + 1e-3)
    return any(swept.difference(near).intersects(sh) for sh in loop.obstacle_shapes)


def _along(planned: NDArray[np.float64], o: NDArray[np.float64], length: float) -> NDArray[np.float64]:
    """Object path (K, 2) [m]: the next ``length`` of the planned path ``planned`` (K, 2) after the
    point nearest to ``o``, translated to start at ``o``."""
    j = int(np.argmin(np.linalg.norm(planned - o, axis=1)))
    rest = planned[j:]
    if len(rest) < 2:
        return np.vstack([o, o])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(rest, axis=0), axis=1))])
    keep = rest[s <= length]
    return keep - keep[0] + o if len(keep) >= 2 else np.vstack([o, o + rest[1] - rest[0]])


def _pair_plan(loop: _Loop, pair: list[str], o: NDArray[np.float64],
               target: NDArray[np.float64]) -> tuple[list[str], float]:
    """The faces of ``pair`` to push this round, and the distance [m] to ``target`` they would leave
    along their expected directions: both faces with 0 left when the rest splits into positive
    shares, else the one face whose push alone comes closest (a single face: its projection)."""
    r = target - o
    us = [loop.unit(f, o) for f in pair]
    rest = [float(np.hypot(*(r - max(0.0, r @ u) * u))) for u in us]
    if len(us) == 2 and abs(np.linalg.det(np.column_stack(us))) >= 1e-6:
        if np.all(np.linalg.solve(np.column_stack(us), r) > 0):
            return list(pair), 0.0
        best = int(np.argmin(rest))
        return [pair[best]], rest[best]
    return [pair[int(np.argmin(rest))]], rest[-1]


def _share(loop: _Loop, pair: list[str], k: int, o: NDArray[np.float64], target: NDArray[np.float64]) -> float:
    """How far [m] face ``pair[k]`` should still push: the remaining displacement split along the
    pair's expected directions at ``o`` (for a single face: the projection on its direction)."""
    r = target - o
    us = [loop.unit(f, o) for f in pair[k:]]
    if len(us) == 1:
        return max(0.0, float(r @ us[0]))
    a = np.column_stack(us)
    if abs(np.linalg.det(a)) < 1e-6:
        return max(0.0, float(r @ us[0]))
    coef = np.linalg.solve(a, r)
    return max(0.0, float(coef[0]))
