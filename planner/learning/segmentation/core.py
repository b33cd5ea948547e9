"""Segmenting one demonstration into pushes and switches (docs/design.md section 5, step 1).

The recordings: the object centre from a camera (about 30 Hz, 1-2 mm noise) and the tool pose from
the Omni's encoders (at least 100 Hz, precise to a few hundredths of a millimetre). A face of the
tool pushes the object when the face touches it (geometry) and the object moves (motion). The
camera alone is too noisy to time a contact (its gaps are good to about a millimetre, i.e. tenths
of a second), so timing comes from the encoders, and the camera only says where the object rests:

1. **Strokes (encoders).** The tool track is smoothed (Savitzky-Golay, cubic, ``tool_smooth``)
   and differentiated; for each face, its velocity along the face's outward normal (turned into the
   world by the tool's heading) gives forward strokes: from where it turns positive to the farthest
   advance before the face falls back by ``r_back`` (a brief dip of the hand does not end a stroke).
   A stroke is a candidate push if the face comes within ``near_tol`` of the object (camera track
   smoothed with a quadratic Savitzky-Golay filter over ``smooth``, in the tool frame).
2. **Contact start (rest + encoders).** Before a push the object rests (quasi-static pushing: it
   moves only while pushed). Its rest position is the mean of the camera samples since the last
   push (noise averages as 1/sqrt(n)); after a push the object also touches the tool as the push
   left it, so that mean is projected onto the curve one radius off the tool outline at that
   instant (least squares under the constraint; exact along the face's normal). Contact starts at
   the first encoder sample where the outline reaches that rest position (interpolated); the
   outline point touching must lie on the stroke's face (``face_tol``), else another part of the
   tool touches and it is not this face's push.
3. **Contact end (encoders).** At the face's farthest advance (where its normal velocity turns
   negative) the face stops pushing and starts to back off, leaving the object at rest (touching
   the tool as it is there). But a hand can linger there, the face within a few hundredths of a
   millimetre of its farthest advance for tens of milliseconds (two submovements cancelling, or
   sliding along the object), and when the contact ends inside that stall the encoders cannot
   tell (their step is about 0.055 mm): the end is the middle of the stall, from the farthest
   advance to where the face has fallen back by ``end_tol``, so the error is at most half the
   stall's length whichever end is the true one.
4. **Spans and motion.** Contacts of one face less than ``merge_gap`` apart are one push (tremor
   can break a contact for a moment, or touch the object again just after the push); then what
   is shorter than ``min_contact`` is a touch; a push must move the object by ``min_move``
   between the rests around it. The simulated operator's ground truth uses the same two span
   rules, in the same order, on the simulator's contact events.
5. **Switches and fixed points.** Between two consecutive pushes of different faces lies a switch,
   with the contact points on the tool (tool frame) and on the object (world) where the first face
   leaves and where the second arrives. The object's rest position during each switch is a fixed
   point (a corner where the active face changes) unless the caller gives the fixed points.

The rest estimates use only the camera samples after the last change of the object's mean
position (:func:`tooltransfer.planner.learning.segmentation.rest.still_tail`, a change-point test whose false alarms are
bounded), so a push that is not found does not spoil the ones after it.

The precision of a contact start is that of the rest position along the face's normal divided
by the speed at which the face approaches it: ``sigma / sqrt(n) / v`` for ``n`` camera samples of
noise ``sigma`` where no earlier contact pins that position (the first push of a demonstration;
after a switch, the new face's normal runs along the old face, where the last contact does not
pin it). For a slow first approach (7 mm/s, 90 samples of 1.5 mm) that is about 23 ms (one
standard deviation); a push that follows one of the same face is pinned by where that one ended.
How close the found contacts come to the simulator's is recorded in ``benchmarks/README.md``
(segmentation); ``tests/test_segmentation.py`` holds every push of the committed dataset to 50 ms.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.oe_skill import DemoPush
from tooltransfer.planner.learning.segmentation.checks import check_recording
from tooltransfer.planner.learning.segmentation.geometry import (
    ToolGeometry,
    nearest_on_segments,
    to_tool_frame,
    to_world,
)
from tooltransfer.planner.learning.segmentation.rest import camera_noise, still_tail
from tooltransfer.problems.dataset import Demonstration
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import OBJECT_RADIUS


@dataclass(frozen=True)
class PushSegment:
    """A push: ``face`` in contact during ``[t_start, t_end]`` [s]; ``samples`` (K,) index the tool
    track inside it; the object rests at ``object_before`` (2,) before and ``object_after`` (2,)
    after it [m]."""

    face: str
    t_start: float
    t_end: float
    samples: NDArray[np.intp]
    object_before: NDArray[np.float64]
    object_after: NDArray[np.float64]


@dataclass(frozen=True)
class SwitchSegment:
    """A switch from ``face_from`` to ``face_to`` during ``[t_start, t_end]`` [s], with the contact
    points (2,) on the tool (tool frame [m]) and on the object (world [m]) where the first face
    leaves and where the second face arrives."""

    face_from: str
    face_to: str
    t_start: float
    t_end: float
    tool_point_from: NDArray[np.float64]
    tool_point_to: NDArray[np.float64]
    object_point_from: NDArray[np.float64]
    object_point_to: NDArray[np.float64]


@dataclass(frozen=True)
class Segmentation:
    """Labels per tool sample (face name or None), pushes, switches, fixed points (F, 2) [m] (the
    corners, or the caller's override), and the smoothed object centre at the tool's times (N, 2)."""

    labels: tuple[str | None, ...]
    pushes: tuple[PushSegment, ...]
    switches: tuple[SwitchSegment, ...]
    fixed_points: NDArray[np.float64]
    object_at_tool: NDArray[np.float64]

    def demo_pushes(self, demo: Demonstration, track: str = "object") -> list[DemoPush]:
        """The pushes as learning input (:class:`tooltransfer.planner.learning.oe_skill.DemoPush`): the object track
        during each push (camera samples, raw) with the tool heading interpolated at those times; each
        push starts where the previous one ended (the object stands still between pushes)."""
        out: list[DemoPush] = []
        for p in self.pushes:
            m = (demo.t_object >= p.t_start) & (demo.t_object <= p.t_end)
            t = demo.t_object[m]
            if t.size < 3:
                continue
            xy = demo.object_xy[m].copy()
            if out:
                xy[0] = out[-1].object_xy[-1]
            yaw = np.interp(t, demo.t_tool, np.unwrap(demo.tool_pose[:, 2]))
            out.append(DemoPush(p.face, t, xy, yaw))
        return out


def _savgol(t: NDArray[np.float64], x: NDArray[np.float64], window: float, order: int) -> NDArray[np.float64]:
    """Savitzky-Golay smoothing along axis 0 of a nearly uniformly sampled signal; window [s]."""
    dt = float(np.median(np.diff(t)))
    n = max(order + 2 + (order % 2 == 0), round(window / dt) // 2 * 2 + 1)
    n = min(n, x.shape[0] if x.shape[0] % 2 else x.shape[0] - 1)
    if n <= order:
        return x.copy()
    return savgol_filter(x, n, order, axis=0, mode="interp")


def _runs(lab: NDArray[np.intp]) -> list[tuple[int, int, int]]:
    """(label, first, last) of each run of equal labels."""
    edges = np.flatnonzero(np.diff(lab)) + 1
    starts = np.concatenate([[0], edges])
    ends = np.concatenate([edges - 1, [lab.size - 1]])
    return [(int(lab[s]), int(s), int(e)) for s, e in zip(starts, ends, strict=True)]



def _strokes(v: NDArray[np.float64], near: NDArray[np.bool_], dt: float, v_on: float, min_advance: float,
             r_back: float) -> list[tuple[int, int]]:
    """Forward strokes of one face: (first, last sample) from where its normal velocity ``v`` (N,)
    [m/s] turns positive to the farthest advance before the face falls back by ``r_back`` [m]
    (so a brief dip of the hand does not end a stroke); kept if the stroke reaches ``v_on``
    [m/s], advances at least ``min_advance`` [m] and comes ``near`` the object."""
    x = np.cumsum(v) * dt
    out: list[tuple[int, int]] = []
    k, n = 0, v.size
    while k < n:
        if v[k] <= 0.0:
            k += 1
            continue
        s0 = top = k
        while k < n and x[k] > x[top] - r_back:
            if x[k] >= x[top]:
                top = k
            k += 1
        if v[s0 : top + 1].max() >= v_on and x[top] - x[s0] >= min_advance and near[s0 : top + 1].any():
            out.append((s0, top))
        k = top + 1
    return out


def _crossing(t: NDArray[np.float64], g: NDArray[np.float64]) -> float | None:
    """First time the gap ``g`` (K,) falls from above 0 to 0 or below, interpolated linearly."""
    hit = np.flatnonzero((g[1:] <= 0.0) & (g[:-1] > 0.0))
    if hit.size == 0:
        return None
    k = int(hit[0]) + 1
    return float(t[k - 1] + (t[k] - t[k - 1]) * g[k - 1] / (g[k - 1] - g[k]))


def _odd_window(t: NDArray[np.float64], window: float) -> int:
    """Odd number of samples spanning about ``window`` [s] (at least 5)."""
    return max(5, round(window / float(np.median(np.diff(t)))) // 2 * 2 + 1)


def _normal_velocity(
    vel: NDArray[np.float64], pose: NDArray[np.float64], normal: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Tool velocity (N,) [m/s] along a face's outward ``normal`` (tool frame) turned into the world."""
    cs, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    return vel[:, 0] * (cs * normal[0] - sn * normal[1]) + vel[:, 1] * (sn * normal[0] + cs * normal[1])


def _zero_down(t: NDArray[np.float64], v: NDArray[np.float64], k: int) -> float:
    """Time [s] where ``v`` crosses zero downwards between samples ``k`` and ``k + 1``
    (interpolated; the last sample if the track ends)."""
    if k + 1 >= v.size or v[k] <= v[k + 1]:
        return float(t[k])
    return float(t[k] + (t[k + 1] - t[k]) * v[k] / (v[k] - v[k + 1]))


def _fall_back(t: NDArray[np.float64], x: NDArray[np.float64], k: int, tol: float) -> float:
    """First time [s] after sample ``k`` where the position ``x`` (N,) [m] has fallen ``tol`` [m]
    below ``x[k]`` (interpolated; the last sample if it never does)."""
    below = np.flatnonzero(x[k + 1 :] < x[k] - tol)
    if below.size == 0:
        return float(t[-1])
    i = k + 1 + int(below[0])
    return float(t[i - 1] + (t[i] - t[i - 1]) * (x[i - 1] - (x[k] - tol)) / (x[i - 1] - x[i]))


_Contact = tuple[int, float, float, NDArray[np.float64], NDArray[np.float64]]
"""A contact found: face index, start and end [s], rest before (2,) [m], tool pose at its end (1, 3)."""


def _merge(found: list[_Contact], gap: float) -> list[_Contact]:
    """Consecutive contacts of one face less than ``gap`` [s] apart joined into one."""
    merged: list[_Contact] = []
    for f in found:
        if merged and merged[-1][0] == f[0] and f[1] - merged[-1][2] < gap:
            merged[-1] = (f[0], merged[-1][1], f[2], merged[-1][3], f[4])
        else:
            merged.append(f)
    return merged


def _pose_at(t: NDArray[np.float64], pose: NDArray[np.float64], when: float) -> NDArray[np.float64]:
    """Tool pose (1, 3) interpolated at time ``when`` [s] (heading unwrapped)."""
    return np.array([[np.interp(when, t, pose[:, j]) for j in range(3)]])


@dataclass(frozen=True)
class _Tracks:
    """One demonstration's smoothed tracks, what every pass of :func:`segment` reads: tool times
    ``t`` (N,) [s] with the smoothed pose (N, 3) [m, rad] and velocity (N, 3), camera times ``t_o``
    (M,) [s] with the smoothed object centre ``obj`` (M, 2) [m] and ``c`` (N, 2) [m] at the tool's
    times; per face (columns in ``names`` order) the gap to the object ``gaps`` (N, F) [m] and the
    velocity along the face's normal ``v_n`` (N, F) [m/s]; the camera noise ``sigma`` [m]."""

    demo: Demonstration
    tool: Tool
    geo: ToolGeometry
    radius: float
    names: list[str]
    t: NDArray[np.float64]
    t_o: NDArray[np.float64]
    dt: float
    pose: NDArray[np.float64]
    obj: NDArray[np.float64]
    c: NDArray[np.float64]
    gaps: NDArray[np.float64]
    v_n: NDArray[np.float64]
    sigma: float

    @classmethod
    def smoothed(cls, demo: Demonstration, tool: Tool, radius: float, smooth: float, tool_smooth: float) -> _Tracks:
        """Smooth the recordings (Savitzky-Golay: cubic over ``tool_smooth`` [s] for the encoders,
        quadratic over ``smooth`` [s] for the camera) and measure each face against the object."""
        t, t_o = demo.t_tool, demo.t_object
        raw = demo.tool_pose.copy()
        raw[:, 2] = np.unwrap(raw[:, 2])
        dt = float(np.median(np.diff(t)))
        pose = savgol_filter(raw, _odd_window(t, tool_smooth), 3, axis=0, mode="interp")
        vel = savgol_filter(raw, _odd_window(t, tool_smooth), 3, deriv=1, delta=dt, axis=0, mode="interp")
        obj = savgol_filter(demo.object_xy, _odd_window(t_o, smooth), 2, axis=0, mode="interp")
        c = np.column_stack([np.interp(t, t_o, obj[:, j]) for j in range(2)])
        geo = ToolGeometry(tool, radius)
        names = list(tool.face_names)
        c_tool = to_tool_frame(c, pose)
        gaps = np.column_stack([geo.face_gap(tool.face(n), c_tool) for n in names])
        v_n = np.column_stack([_normal_velocity(vel, pose, tool.face(n).normal) for n in names])
        return cls(demo, tool, geo, radius, names, t, t_o, dt, pose, obj, c, gaps, v_n, camera_noise(demo.object_xy))

    def rest(self, t0: float, t1: float, after: NDArray[np.float64] | None,
             fallback: NDArray[np.float64] | None = None) -> NDArray[np.float64] | None:
        """Rest position (2,) from the camera samples in [t0, t1], projected onto the curve one
        radius off the outline at pose ``after`` (1, 3) when the rest follows a contact. With
        fewer than 3 samples: None, or with a ``fallback`` pose the smoothed track at ``t0``
        projected onto the outline at that pose. Only the samples after the object's last move count
        (:func:`tooltransfer.planner.learning.segmentation.rest.still_tail`), so a push not found does not spoil the
        next rest."""
        t_o, obj, demo = self.t_o, self.obj, self.demo
        idx = np.flatnonzero((t_o >= t0) & (t_o <= t1))
        if idx.size >= 3:
            idx, whole = still_tail(demo.object_xy, idx, self.sigma)
            p = demo.object_xy[idx].mean(axis=0)
            if not whole:  # the object moved after t0 (a push not found): no longer where it was left
                after = None
        elif fallback is not None:
            p, after = np.array([np.interp(t0, t_o, obj[:, 0]), np.interp(t0, t_o, obj[:, 1])]), fallback
        else:
            return None
        if after is None:
            return p
        q = to_tool_frame(p, after)
        _, near = self.geo.outline_gap(q)
        u = q - near
        n = float(np.hypot(*u[0]))
        return p if n == 0.0 else to_world(near + self.radius * u / n, after)[0]

    def touches_face(self, p: NDArray[np.float64], when: float, j: int, face_tol: float) -> bool:
        """Whether the outline point nearest the object at ``p`` (2,) lies on face ``j`` (within
        ``face_tol`` [m]) with the tool at its pose at time ``when`` [s]."""
        _, near = self.geo.outline_gap(to_tool_frame(p, _pose_at(self.t, self.pose, when)))
        a, b = self.tool.face(self.names[j]).contact_segment()
        return float(nearest_on_segments(near, a[None], b[None])[0][0]) <= face_tol

    def start_of(self, before: NDArray[np.float64], s0: int, e0: int) -> float | None:
        """When [s] the outline first reaches the object resting at ``before`` (2,) during the
        stroke of samples ``s0..e0`` (None if it never does)."""
        seg = slice(s0, e0 + 1)
        return _crossing(self.t[seg], self.geo.outline_gap(to_tool_frame(before, self.pose[seg]))[0])


def _contacts(tr: _Tracks, strokes: list[tuple[int, int, int]], *, near_tol: float, end_tol: float, face_tol: float,
              settle: float) -> list[_Contact]:
    """Pass 1, in time order: the contacts of the ``strokes`` (first, last sample, face index);
    each rest lasts from one contact's end to the next one's start (module docstring, steps 2-3)."""
    t, t_o, obj, v_n = tr.t, tr.t_o, tr.obj, tr.v_n
    found: list[_Contact] = []
    prev_end, prev_pose = float(min(t_o[0], t[0])) - settle, None
    prev_face = -1
    for s0, e0, j in strokes:
        s0 = max(s0, int(np.searchsorted(t, prev_end, side="right")))  # after the last contact only
        if s0 >= e0:
            continue
        # a rest needs camera samples, except a short break in one face's push: there the object
        # is where that push left it (the smoothed track, projected onto the outline)
        after = prev_pose if j == prev_face else None
        close = np.flatnonzero(tr.gaps[s0 : e0 + 1, j] < near_tol)  # still short of contact: rest until here
        t_rest = float(t[s0 + int(close[0]) if close.size else s0])
        before = tr.rest(prev_end + settle, t_rest, prev_pose, after)
        if before is None:  # hardly any camera sample yet: start from the smoothed track
            before = np.array([np.interp(t_rest, t_o, obj[:, 0]), np.interp(t_rest, t_o, obj[:, 1])])
        t_start = tr.start_of(before, s0, e0)
        for _ in range(2):  # the rest lasted until contact: use all of it and look again
            longer = None if t_start is None else tr.rest(prev_end + settle, t_start, prev_pose, after)
            if longer is None:
                break
            before, t_start = longer, tr.start_of(longer, s0, e0)
        if t_start is None:
            continue  # the stroke stopped short of the object
        if not tr.touches_face(before, t_start, j, face_tol):
            continue  # another part of the tool touches: not this face's push
        t_top = _zero_down(t, v_n[:, j], e0)  # the farthest advance: the object is left touching here
        t_end = 0.5 * (t_top + _fall_back(t, np.cumsum(v_n[:, j]) * tr.dt, e0, end_tol))
        end_pose = _pose_at(t, tr.pose, t_top)
        found.append((j, t_start, t_end, before, end_pose))
        prev_end, prev_pose, prev_face = t_end, end_pose, j
    return found


def _pushes(tr: _Tracks, merged: list[_Contact], *, settle: float, min_move: float) -> list[PushSegment]:
    """Pass 3: the contacts that moved the object by at least ``min_move`` [m] between the rests
    around them (a touch that moved nothing is not a push)."""
    pushes: list[PushSegment] = []
    for i, (j, t_start, t_end, before, end_pose) in enumerate(merged):
        nxt = merged[i + 1][1] if i + 1 < len(merged) else float(tr.t_o[-1])
        after = tr.rest(t_end + settle, nxt, end_pose)
        if after is None or np.hypot(*(after - before)) < min_move:
            continue  # a touch that moved nothing: not a push
        samples = np.flatnonzero((tr.t >= t_start) & (tr.t <= t_end))
        pushes.append(PushSegment(tr.names[j], t_start, t_end, samples, before, after))
    return pushes


def segment(
    demo: Demonstration,
    tool: Tool,
    *,
    radius: float = OBJECT_RADIUS,
    smooth: float = 0.3,
    tool_smooth: float = 0.09,
    near_tol: float = 0.003,
    v_on: float = 0.002,
    min_advance: float = 0.0001,
    r_back: float = 0.00005,
    end_tol: float = 0.00003,
    min_contact: float = 0.05,
    merge_gap: float = 0.2,
    face_tol: float = 0.002,
    settle: float = 0.1,
    min_move: float = 0.001,
    fixed_points: Sequence[Sequence[float]] | None = None,
) -> Segmentation:
    """Segment one demonstration made with ``tool`` (method in the module docstring).

    Args:
        demo: the recordings; tool: the demonstration tool; radius: the object's radius [m].
        smooth, tool_smooth: Savitzky-Golay windows [s] of the object track and of the tool track.
        near_tol: gap [m] between a face and the smoothed object within which a stroke of that face
            is a candidate push.
        v_on, min_advance: a stroke reaches at least ``v_on`` [m/s] along the face's normal and
            advances at least ``min_advance`` [m]; it ends where the face is farthest forward
            before falling back by ``r_back`` [m].
        end_tol: the face lingers at its farthest advance while within ``end_tol`` [m] of it (half
            the encoders' step, above the smoothed track's jitter of a few micrometres); the
            contact ends midway through that stall.
        min_contact, merge_gap: contacts shorter than ``min_contact`` [s] are touches, not pushes;
            contacts of one face less than ``merge_gap`` [s] apart are one push.
        face_tol: a contact belongs to a stroke's face only if the outline point nearest the
            object lies within ``face_tol`` [m] of that face's contact segment.
        settle: time [s] after a push's end before the object counts as resting.
        min_move: least object displacement [m] for a contact to count as a push.
        fixed_points: manual override of the fixed points (F, 2) [m]; None: the corners found.

    Returns:
        The :class:`Segmentation`.
    """
    t, t_o = demo.t_tool, demo.t_object
    if t.size < 10 or t_o.size < 10:
        raise InputError(f"{demo.name}", "a demonstration with at least 10 tool and 10 object samples",
                         f"{t.size} tool, {t_o.size} object")
    check_recording(demo, tool)  # loaded from files: the kinematics and the contacts against the declared tool
    tr = _Tracks.smoothed(demo, tool, radius, smooth, tool_smooth)
    strokes = sorted(
        (s0, e0, j)
        for j in range(len(tr.names))
        for s0, e0 in _strokes(tr.v_n[:, j], tr.gaps[:, j] < near_tol, tr.dt, v_on, min_advance, r_back)
    )
    found = _contacts(tr, strokes, near_tol=near_tol, end_tol=end_tol, face_tol=face_tol, settle=settle)
    # pass 2: contacts of one face less than merge_gap apart are one push (the hand's tremor can
    # break a contact for a moment, or touch again just after a push), then what is shorter than
    # min_contact is a touch (in this order, as the ground truth's rules); dropping a touch of
    # another face can bring two contacts of one face together
    merged = _merge(found, merge_gap)
    merged = _merge([f for f in merged if f[2] - f[1] >= min_contact], merge_gap)
    pushes = _pushes(tr, merged, settle=settle, min_move=min_move)
    labels: list[str | None] = [None] * t.size
    for p in pushes:
        for k in p.samples:
            labels[k] = p.face
    switches = [_switch(p, q, t, tr.pose, tr.geo, radius) for p, q in itertools.pairwise(pushes) if p.face != q.face]
    if fixed_points is not None:
        fixed = fixed_point_array(fixed_points, f"fixed_points ({demo.name})")
    else:
        fixed = np.array([p.object_after for p, q in itertools.pairwise(pushes) if p.face != q.face]).reshape(-1, 2)
    return Segmentation(tuple(labels), tuple(pushes), tuple(switches), fixed, tr.c)


def _switch(p: PushSegment, q: PushSegment, t: NDArray[np.float64], pose: NDArray[np.float64], geo: ToolGeometry,
            radius: float) -> SwitchSegment:
    """The switch between push ``p`` and push ``q``: contact points where ``p`` ends and ``q`` starts."""
    pts = []
    for when, centre in ((p.t_end, p.object_after), (q.t_start, q.object_before)):
        at = _pose_at(t, pose, when)
        c_t = to_tool_frame(centre, at)
        _, near = geo.outline_gap(c_t)
        u = near - c_t
        obj_point = centre + radius * to_world(u / max(float(np.hypot(*u[0])), 1e-12), at * [0, 0, 1])[0]
        pts.append((near[0], obj_point))
    return SwitchSegment(p.face, q.face, p.t_end, q.t_start, pts[0][0], pts[1][0], pts[0][1], pts[1][1])


def fixed_point_array(points: object, field: str = "fixed_points") -> NDArray[np.float64]:
    """Fixed points as an (F, 2) array [m]: a list of ``[x, y]`` pairs of finite numbers (not booleans
    or strings); errors name ``field`` and the entry."""
    if not isinstance(points, list | tuple | np.ndarray):
        raise InputError(field, "a list of [x, y] points [m]", type(points).__name__)
    for i, pt in enumerate(points):
        if not isinstance(pt, list | tuple | np.ndarray) or len(pt) != 2:
            raise InputError(f"{field}[{i}]", "a point [x, y] [m]", repr(pt)[:60])
        for j, v in enumerate(pt):
            if isinstance(v, bool | np.bool_) or not isinstance(v, int | float | np.integer | np.floating) \
                    or not np.isfinite(v):
                raise InputError(f"{field}[{i}][{j}]", "a finite number [m]", repr(v)[:60])
    return np.asarray(points, dtype=np.float64).reshape(-1, 2)


def load_fixed_points(path: str | Path, names: Sequence[str] = (), option: str = "--fixed-points"
                      ) -> dict[str, NDArray[np.float64]]:
    """A ``--fixed-points`` file: JSON ``{demo name: [[x, y], ...]}`` [m]; every entry checked (and,
    given ``names``, every key a demonstration's name), errors naming the ``option``, the file and the
    entry."""
    import json

    where = f"{option} {path}".strip()
    try:
        p = Path(path)
        if p.stat().st_size > 16 * 2**20:
            raise InputError(f"{where}", "a fixed-points file of at most 16 MB", f"{p.stat().st_size} bytes")
        data = json.loads(p.read_bytes().decode("utf-8-sig"))
    except OSError as exc:
        raise InputError(f"{where}", "a readable JSON file {demo name: [[x, y], ...]} [m]", exc.strerror) from None
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise InputError(f"{where}", "a JSON file {demo name: [[x, y], ...]} [m]",
                         str(exc)[:120] if not isinstance(exc, RecursionError) else "JSON nested too deep") from None
    if not isinstance(data, dict):
        raise InputError(f"{where}", "a JSON object {demo name: [[x, y], ...]} [m]", type(data).__name__)
    out = {}
    for name, pts in data.items():
        if names and name not in names:
            raise InputError(f"{where}: {name[:60]}", f"a demonstration's name ({', '.join(names)})", repr(name[:60]))
        out[name] = fixed_point_array(pts, f"{where}: {name[:60]}")
    return out
