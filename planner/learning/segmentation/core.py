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

The smoothed tracks are in :mod:`tooltransfer.planner.learning.segmentation.tracks`, the strokes and contacts of
steps 1-4 in :mod:`tooltransfer.planner.learning.segmentation.contacts`, the caller's fixed points in
:mod:`tooltransfer.planner.learning.segmentation.fixed_points`.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.oe_skill import DemoPush
from tooltransfer.planner.learning.segmentation.checks import check_recording
from tooltransfer.planner.learning.segmentation.contacts import Contact, face_strokes, find_contacts, merge_contacts
from tooltransfer.planner.learning.segmentation.fixed_points import fixed_point_array
from tooltransfer.planner.learning.segmentation.geometry import ToolGeometry, to_tool_frame, to_world
from tooltransfer.planner.learning.segmentation.tracks import Tracks, pose_at
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


def _pushes(tr: Tracks, merged: list[Contact], *, settle: float, min_move: float) -> list[PushSegment]:
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
    tr = Tracks.smoothed(demo, tool, radius, smooth, tool_smooth)
    strokes = sorted(
        (s0, e0, j)
        for j in range(len(tr.names))
        for s0, e0 in face_strokes(tr.v_n[:, j], tr.gaps[:, j] < near_tol, tr.dt, v_on, min_advance, r_back)
    )
    found = find_contacts(tr, strokes, near_tol=near_tol, end_tol=end_tol, face_tol=face_tol, settle=settle)
    # pass 2: contacts of one face less than merge_gap apart are one push (the hand's tremor can
    # break a contact for a moment, or touch again just after a push), then what is shorter than
    # min_contact is a touch (in this order, as the ground truth's rules); dropping a touch of
    # another face can bring two contacts of one face together
    merged = merge_contacts(found, merge_gap)
    merged = merge_contacts([f for f in merged if f[2] - f[1] >= min_contact], merge_gap)
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
        at = pose_at(t, pose, when)
        c_t = to_tool_frame(centre, at)
        _, near = geo.outline_gap(c_t)
        u = near - c_t
        obj_point = centre + radius * to_world(u / max(float(np.hypot(*u[0])), 1e-12), at * [0, 0, 1])[0]
        pts.append((near[0], obj_point))
    return SwitchSegment(p.face, q.face, p.t_end, q.t_start, pts[0][0], pts[1][0], pts[0][1], pts[1][1])
