"""From a push plan to the whole tool motion: approach, pushes, switches, retreat, timed and jointed.

Timeline (docs/design.md section 1; the object stands still outside the pushes):

1. approach: from ``approach_distance`` behind the first contact pose (along the face's normal
   there, so the tool meets the object where the push starts; halved until the move is within the
   Omni's reach, turned up to 75 degrees from the normal where no length is) to it, a minimum-jerk
   straight move;
2. pushes: the condensed object motion with the tool poses of the inverse push model (each push's
   ``tool_pose``: the contact rolling along the face, heading as the Omni imposes it), timed by the
   OE motion stretched by one factor so that the tool keeps within the maximum speed and
   acceleration;
3. between consecutive pushes a switch (a change of face) or a re-contact (the same face touching
   again elsewhere): the tool path from the switch or re-contact planner (:class:`SwitchPath`),
   timed by a minimum-jerk arc-length profile within the limits;
4. retreat: back off ``approach_distance`` along the last contact's normal.

Joints come from the vectorized inverse kinematics of the whole tool path (limits checked).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from shapely import Polygon

from tooltransfer.errors import ToolTransferError
from tooltransfer.planner.planning.oe.push_plan import Push, PushPlan
from tooltransfer.planner.planning.ss.result import SwitchPath
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN, tool_obstacle_clearance
from tooltransfer.timing import min_jerk_along, min_jerk_duration, stretch_factor
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import rotation

SwitchPlanner = Callable[[NDArray[np.float64], str, NDArray[np.float64], str, NDArray[np.float64]], SwitchPath]
"""``planner(object_xy (2,), face_a, pose_a (3,), face_b, pose_b (3,)) -> SwitchPath``."""


@dataclass(frozen=True)
class Motion:
    """The timed whole motion: equal-length sample arrays and the pieces' time intervals."""

    t: NDArray[np.float64]
    object_xy: NDArray[np.float64]
    tool_pose: NDArray[np.float64]
    joints: NDArray[np.float64]
    joint_violation: NDArray[np.float64]
    phase: tuple[str, ...]
    face: tuple[str | None, ...]
    pushes: tuple[tuple[str, float, float, float], ...]
    switches: tuple[tuple[str, str, float, float, SwitchPath], ...]
    stretch: float


#: Turns [rad] from a straight back-off tried in turn where the straight one is not clear (here, and in
#: the closed loop's back-off from a contact): each keeps a component along the contact's normal.
BACK_OFF_TURNS = tuple(float(a) for a in np.radians([0.0, 20.0, -20.0, 40.0, -40.0]))
#: Turns [rad] a plan's approach and retreat try after :data:`BACK_OFF_TURNS` where none of those keeps the
#: move within the Omni's reach (a contact pose at the edge of its workspace, the limit across the face's
#: normal): the tool comes in mostly along the face, 1 mm and 0.5 mm toward the object per 2 mm of move,
#: taken only where its outline keeps off the resting object everywhere but at the contact (a concave
#: tool's other leg may sweep it).
WIDE_TURNS = tuple(float(a) for a in np.radians([60.0, -60.0, 75.0, -75.0]))


def _reachable_back(platform: OmniPlatform, at: NDArray[np.float64], direction: float,
                    distance: float, tool: Tool | None = None, obstacles: Sequence[Disc | Polygon] = (),
                    puck: Disc | None = None) -> NDArray[np.float64]:
    """Offset (2,) backing off from ``at`` against ``direction`` [rad] by ``distance`` [m], halved
    until the whole straight move stays within the Omni's reach (at least 2 mm) with the ``tool``'s
    outline :data:`~tooltransfer.planner.planning.tool_clearance.TOOL_MARGIN` from the ``obstacles`` (at
    the heading the Omni imposes: the margin of a solved plan); when no length along
    ``direction`` does, directions 20 and 40 degrees to either side are tried (the tool still meets
    the object where the push starts, a little obliquely), then :data:`WIDE_TURNS` (with the ``tool`` and
    the resting ``puck``, where its outline keeps off the puck but at the contact)."""
    wide = WIDE_TURNS if tool is not None and puck is not None else ()
    # the puck less 1 um: the outline at a wide turn's poses but the contact keeps off it
    off = [] if puck is None else [Disc(puck.centre, puck.radius - 1e-6)]
    for turn in BACK_OFF_TURNS + wide:
        u = -np.array([np.cos(direction + turn), np.sin(direction + turn)])
        d = distance
        while d >= 0.002:
            line = at + np.linspace(0.0, d, 20)[:, None] * u
            jp = joint_path(platform, line)
            poses = np.column_stack([line, jp.heading])
            if np.all(jp.violation == 0.0) and (
                    tool is None or not obstacles or tool_obstacle_clearance(tool, poses, obstacles).distance
                    >= TOOL_MARGIN) and (turn not in wide or tool_obstacle_clearance(tool, poses[1:], off).distance
                                         > 0.0):
                return d * u
            d /= 2
    return -0.002 * np.array([np.cos(direction), np.sin(direction)])


def _line(a: NDArray[np.float64], b: NDArray[np.float64], v_max: float, a_max: float,
          dt: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    dur = min_jerk_duration(float(np.linalg.norm(b - a)), v_max, a_max)
    n = max(2, int(np.ceil(dur / dt)) + 1)
    return min_jerk_along(np.vstack([a, b]), dur, n)


def _resting(plan: PushPlan, k: int, radius: float | None) -> Disc | None:
    """The object resting at ``plan``'s sample ``k``, a disc of ``radius`` [m] (None without one)."""
    return None if radius is None else Disc(tuple(float(v) for v in plan.object_xy[k]), radius)


def _normal_angle(tool: Tool, push: Push, at: int) -> float:
    """World angle [rad] of the pushing face's outward normal at sample ``at`` of ``push``."""
    n = rotation(float(push.tool_pose[at, 2])) @ tool.face(push.face).normal
    return float(np.arctan2(n[1], n[0]))


def assemble(
    plan: PushPlan,
    tool: Tool,
    platform: OmniPlatform,
    switch: SwitchPlanner,
    recontact: SwitchPlanner,
    *,
    v_max: float,
    a_max: float,
    approach_distance: float,
    dt: float = 0.01,
    obstacles: Sequence[Disc | Polygon] = (),
    puck_radius: float | None = None,
) -> Motion:
    """Assemble the timed tool motion of a solved push plan (see the module docstring).

    Args:
        plan: a solved push plan (its pushes carry their tool poses); tool: its tool.
        switch: plans each change of face; recontact: each re-contact of the same face.
        v_max, a_max: tool speed [m/s] and acceleration [m/s^2] limits; approach_distance: [m].
        dt: sample spacing [s] of approach, switches and retreat (pushes keep the plan's samples).
        obstacles: what the approach and the retreat keep the tool's outline clear of, where a
            direction of theirs allows it.
        puck_radius: the object's radius [m]; with it, an approach or retreat turned by
            :data:`WIDE_TURNS` keeps the outline off the resting object (without it none is).
    """
    pushes = plan.pushes
    poses = [p.tool_pose for p in pushes]
    c = max(stretch_factor(plan.t[p.samples], pp[:, :2], v_max, a_max) for p, pp in zip(pushes, poses, strict=True))
    t_parts: list[NDArray[np.float64]] = []
    obj_parts: list[NDArray[np.float64]] = []
    xy_parts: list[NDArray[np.float64]] = []
    phases: list[str] = []
    faces: list[str | None] = []
    push_spans: list[tuple[str, float, float, float]] = []
    switch_spans: list[tuple[str, str, float, float, SwitchPath]] = []
    now = 0.0

    def add(tt: NDArray[np.float64], obj: NDArray[np.float64], xy: NDArray[np.float64], phase: str,
            face: str | None) -> None:
        nonlocal now
        keep = slice(1, None) if t_parts else slice(None)  # consecutive pieces share an end sample
        t_parts.append(now + tt[keep] - tt[0])
        obj_parts.append(obj[keep])
        xy_parts.append(xy[keep])
        phases.extend([phase] * len(tt[keep]))
        faces.extend([face] * len(tt[keep]))
        now = float(t_parts[-1][-1]) if len(t_parts[-1]) else now

    first, last = pushes[0], pushes[-1]
    back0 = _reachable_back(platform, poses[0][0, :2], _normal_angle(tool, first, 0), approach_distance, tool,
                            obstacles, _resting(plan, first.samples[0], puck_radius))
    tt, xy = _line(poses[0][0, :2] + back0, poses[0][0, :2], v_max, a_max, dt)
    add(tt, np.repeat(plan.object_xy[first.samples[:1]], len(tt), axis=0), xy, "approach", None)
    for i, p in enumerate(pushes):
        start = now
        add(c * plan.t[p.samples], plan.object_xy[p.samples], poses[i][:, :2], "push", p.face)
        push_spans.append((p.face, start, now, p.direction))
        if i + 1 < len(pushes):
            nxt = pushes[i + 1]
            obj = plan.object_xy[p.samples[-1]]
            planner = recontact if nxt.recontact else switch
            sw = planner(obj, p.face, poses[i][-1], nxt.face, poses[i + 1][0])
            if sw.status != "solved":
                raise SwitchFailed(p.face, nxt.face, sw.reason, where=obj)
            length = float(np.sum(np.linalg.norm(np.diff(sw.xy, axis=0), axis=1)))
            dur = min_jerk_duration(length, v_max, a_max)
            n = max(2, int(np.ceil(dur / dt)) + 1)
            tt, xy = min_jerk_along(sw.xy, dur, n)
            start = now
            add(tt, np.repeat(obj[None], n, axis=0), xy, "switch", None)
            switch_spans.append((p.face, nxt.face, start, now, sw))
    end = poses[-1][-1, :2]
    back1 = _reachable_back(platform, end, _normal_angle(tool, last, -1), approach_distance, tool, obstacles,
                            _resting(plan, last.samples[-1], puck_radius))
    tt, xy = _line(end, end + back1, v_max, a_max, dt)
    add(tt, np.repeat(plan.object_xy[last.samples[-1:]], len(tt), axis=0), xy, "retreat", None)
    t = np.concatenate(t_parts)
    tool_xy = np.concatenate(xy_parts)
    jp = joint_path(platform, tool_xy)
    pose = np.column_stack([tool_xy, jp.heading])
    return Motion(t, np.concatenate(obj_parts), pose, jp.q, jp.violation, tuple(phases), tuple(faces),
                  tuple(push_spans), tuple(switch_spans), c)


class SwitchFailed(ToolTransferError):
    """A switch between two pushes has no admissible tool path; ``where``: the object's centre (2,) [m]
    while it should be made, where known."""

    def __init__(self, face_a: str, face_b: str, reason: str, where: NDArray[np.float64] | None = None) -> None:
        self.face_a, self.face_b, self.reason = face_a, face_b, reason
        self.where = None if where is None else np.array(where, dtype=np.float64)
        super().__init__(f"switch {face_a} -> {face_b}: {reason}")


def switch_clearances(motion: Motion) -> Sequence[float]:
    """Min clearance [m] of each switch, as its planner measured it."""
    return [sw.object_clearance for *_, sw in motion.switches]
