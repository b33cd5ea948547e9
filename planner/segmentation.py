"""Segmenting a demonstration into pushes and switches (DESIGN section 5, step 1).

Every tool sample gets the face in contact with the object, or none, from the geometry: the
object's centre (the camera track smoothed by a Savitzky-Golay filter and interpolated at the tool's
times) against each face of the tool placed at its recorded pose; a face is in contact when the
object is on its outer side and its edge is within ``tol`` of the face's contact range, and it
stays so until the gap exceeds ``tol_out`` (hysteresis). Noise still makes the labels flicker at
the edges of contact, so runs of one label shorter than ``min_run``
are dropped and gaps shorter than ``min_gap`` inside one face's contact are filled. Runs of a face
are the pushes; between two pushes of different faces lies a switch (with the contact points on the
tool and on the object at both ends); the object position at each switch is a fixed point (a corner),
unless the caller overrides the fixed points.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from dmp.errors import InputError
from planner.oe.learn import DemoPush
from problems.dataset import Demonstration
from tools.model import Tool
from tools.objects import OBJECT_RADIUS


@dataclass(frozen=True)
class PushSegment:
    """A push: ``face`` in contact during ``[t_start, t_end]`` [s]; ``samples`` index the tool track."""

    face: str
    t_start: float
    t_end: float
    samples: NDArray[np.intp]


@dataclass(frozen=True)
class SwitchSegment:
    """A switch from ``face_from`` to ``face_to`` during ``[t_start, t_end]`` [s], with the contact
    points on the tool (tool frame) and on the object (world) where it leaves and where it arrives."""

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
    """Labels per tool sample (face name or None), pushes, switches, fixed points (F, 2) [m], and the
    smoothed object centre at the tool's times (N, 2) [m]."""

    labels: tuple[str | None, ...]
    pushes: tuple[PushSegment, ...]
    switches: tuple[SwitchSegment, ...]
    fixed_points: NDArray[np.float64]
    object_at_tool: NDArray[np.float64]

    def demo_pushes(self, demo: Demonstration, track: str = "object") -> list[DemoPush]:
        """The pushes as learning input (:class:`planner.oe.learn.DemoPush`): the object track during
        each push (camera samples, raw) with the tool heading interpolated at those times; each
        push starts where the previous one ended (the object stands still during a switch)."""
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


def _smooth_track(
    t: NDArray[np.float64], xy: NDArray[np.float64], window: float, deriv: int = 0
) -> NDArray[np.float64]:
    """Savitzky-Golay smoothing (quadratic) of a nearly uniformly sampled track, or its derivative."""
    dt = float(np.median(np.diff(t)))
    n = max(5, round(window / dt) // 2 * 2 + 1)
    n = min(n, xy.shape[0] if xy.shape[0] % 2 else xy.shape[0] - 1)
    return savgol_filter(xy, n, 2, deriv=deriv, delta=dt, axis=0, mode="interp")


def _runs(lab: NDArray[np.intp]) -> list[tuple[int, int, int]]:
    """(label, first, last) of each run of equal labels."""
    edges = np.flatnonzero(np.diff(lab)) + 1
    starts = np.concatenate([[0], edges])
    ends = np.concatenate([edges - 1, [lab.size - 1]])
    return [(int(lab[s]), int(s), int(e)) for s, e in zip(starts, ends, strict=True)]


def segment(
    demo: Demonstration,
    tool: Tool,
    *,
    radius: float = OBJECT_RADIUS,
    tol: float = 0.001,
    tol_out: float = 0.0022,
    min_run: float = 0.15,
    min_gap: float = 0.08,
    smooth: float = 0.3,
    rest: float = 0.4,
    touch: float = 0.0003,
    fixed_points: Sequence[Sequence[float]] | None = None,
) -> Segmentation:
    """Segment one demonstration made with ``tool`` (see the module docstring).

    Args:
        demo: the recordings; tool: the demonstration tool; radius: the object's radius [m].
        tol, tol_out: contact starts when the gap falls below ``tol`` and ends when it exceeds
            ``tol_out`` [m] (the camera's noise, smoothed, is about half a millimetre).
        min_run, min_gap: shortest contact run and longest gap filled inside one contact [s].
        smooth: Savitzky-Golay window of the object track [s].
        rest: how long [s] the object rests before and after a push (its rest position is the
            median of the camera samples there); touch: gap [m] of the face's precise track to that
            rest position at which contact starts and ends.
        fixed_points: manual override of the fixed points (F, 2) [m].
    """
    if demo.t_tool.size < 3 or demo.t_object.size < 5:
        raise InputError("demo", "a demonstration with tool and object tracks", demo.name)
    obj = _smooth_track(demo.t_object, demo.object_xy, smooth)
    c = np.column_stack([np.interp(demo.t_tool, demo.t_object, obj[:, j]) for j in range(2)])
    pose = demo.tool_pose
    cs, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])

    def world(p: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.column_stack([pose[:, 0] + cs * p[0] - sn * p[1], pose[:, 1] + sn * p[0] + cs * p[1]])

    names = list(tool.face_names)
    gaps = np.full((len(pose), len(names)), np.inf)
    for j, name in enumerate(names):
        f = tool.face(name)
        a, b = (world(p) for p in f.contact_segment())
        n = np.column_stack([cs * f.normal[0] - sn * f.normal[1], sn * f.normal[0] + cs * f.normal[1]])
        ab = b - a
        s = np.clip(np.einsum("ij,ij->i", c - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18), 0, 1)
        d = np.linalg.norm(c - (a + s[:, None] * ab), axis=1) - radius
        outside = np.einsum("ij,ij->i", c - a, n) > 0
        gaps[outside, j] = d[outside]
    # hysteresis: contact starts below tol and lasts until the gap exceeds tol_out
    best, near = np.argmin(gaps, axis=1), gaps.min(axis=1)
    lab = np.full(len(pose), -1)
    cur = -1
    for i in range(len(pose)):
        if cur == -1:
            cur = int(best[i]) if near[i] < tol else -1
        elif gaps[i, cur] > tol_out:
            cur = int(best[i]) if near[i] < tol else -1
        lab[i] = cur
    dt = float(np.median(np.diff(demo.t_tool)))
    for _ in range(2):  # fill short gaps within one face's contact, then drop short runs
        runs = _runs(lab)
        for i, (v, s0, e0) in enumerate(runs):
            if v == -1 and 0 < i < len(runs) - 1 and runs[i - 1][0] == runs[i + 1][0] != -1:
                if (e0 - s0 + 1) * dt < min_gap:
                    lab[s0 : e0 + 1] = runs[i - 1][0]
        for v, s0, e0 in _runs(lab):
            if v != -1 and (e0 - s0 + 1) * dt < min_run:
                lab[s0 : e0 + 1] = -1
    t = demo.t_tool
    # Timing from the encoders: before a push and after it the object rests, and its rest position
    # is the median of many camera samples (noise averages out); the face's precise track against
    # that position says when contact starts and ends.
    pushes = []
    gap_of = {name: _face_gap(tool.face(name), pose, radius) for name in names}
    for v, s0, e0 in _runs(lab):
        if v == -1:
            continue
        name = names[v]
        before = demo.object_xy[(demo.t_object >= t[s0] - rest) & (demo.t_object <= t[s0])]
        after = demo.object_xy[(demo.t_object >= t[e0]) & (demo.t_object <= t[e0] + rest)]
        if len(before) < 3 or len(after) < 3:
            pushes.append(PushSegment(name, float(t[s0]), float(t[e0]), np.arange(s0, e0 + 1)))
            continue
        lo = int(np.searchsorted(t, t[s0] - rest))
        hi = int(np.searchsorted(t, t[e0] + rest, side="right"))
        g0 = gap_of[name](np.median(before, axis=0))[lo:hi]
        g1 = gap_of[name](np.median(after, axis=0))[lo:hi]
        touch0, touch1 = np.flatnonzero(g0 < touch), np.flatnonzero(g1 < touch)
        a = lo + int(touch0[0]) if touch0.size else s0
        b = lo + int(touch1[-1]) if touch1.size else e0
        if b <= a:
            continue
        lab[s0 : e0 + 1] = -1
        lab[a : b + 1] = v
        pushes.append(PushSegment(name, float(t[a]), float(t[b]), np.arange(a, b + 1)))
    switches = []
    for p, q in itertools.pairwise(pushes):
        if p.face == q.face:
            continue
        i, k = int(p.samples[-1]), int(q.samples[0])
        fp, fq = tool.face(p.face), tool.face(q.face)
        switches.append(SwitchSegment(
            p.face, q.face, p.t_end, q.t_start,
            _contact_point(fp, pose[i], c[i]), _contact_point(fq, pose[k], c[k]),
            c[i] - radius * _unit(c[i] - _closest(fp, pose[i], c[i])),
            c[k] - radius * _unit(c[k] - _closest(fq, pose[k], c[k])),
        ))
    if fixed_points is not None:
        fixed = np.asarray(fixed_points, dtype=np.float64).reshape(-1, 2)
    else:
        fixed = np.array([c[(np.abs(t - 0.5 * (s.t_start + s.t_end))).argmin()] for s in switches]).reshape(-1, 2)
    labels = tuple(None if v == -1 else names[v] for v in lab)
    return Segmentation(labels, tuple(pushes), tuple(switches), fixed, c)


def _face_gap(face, pose: NDArray[np.float64], radius: float):
    """``gap(c) -> (N,)``: distance [m] from the face's contact range (tool at ``pose`` (N, 3)) to
    the edge of the object centred at ``c`` (2,); inf where the object is behind the face."""
    cs, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    a, b = (np.column_stack([pose[:, 0] + cs * p[0] - sn * p[1], pose[:, 1] + sn * p[0] + cs * p[1]])
            for p in face.contact_segment())
    n = np.column_stack([cs * face.normal[0] - sn * face.normal[1], sn * face.normal[0] + cs * face.normal[1]])
    ab = b - a

    def gap(c: NDArray[np.float64]) -> NDArray[np.float64]:
        s = np.clip(np.einsum("ij,ij->i", c - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18), 0, 1)
        d = np.linalg.norm(c - (a + s[:, None] * ab), axis=1) - radius
        return np.where(np.einsum("ij,ij->i", c - a, n) > 0, d, np.inf)

    return gap


def _unit(v: NDArray[np.float64]) -> NDArray[np.float64]:
    n = float(np.hypot(*v))
    return v / n if n > 0 else v


def _closest(face, pose: NDArray[np.float64], c: NDArray[np.float64]) -> NDArray[np.float64]:
    """World point of ``face`` (tool at ``pose``) nearest the object centre ``c``."""
    cs, sn = np.cos(pose[2]), np.sin(pose[2])
    rot = np.array([[cs, -sn], [sn, cs]])
    a, b = (pose[:2] + rot @ p for p in face.contact_segment())
    s = float(np.clip((c - a) @ (b - a) / max((b - a) @ (b - a), 1e-18), 0, 1))
    return a + s * (b - a)


def _contact_point(face, pose: NDArray[np.float64], c: NDArray[np.float64]) -> NDArray[np.float64]:
    """The contact point on the tool, in the tool frame [m]."""
    cs, sn = np.cos(pose[2]), np.sin(pose[2])
    rot = np.array([[cs, -sn], [sn, cs]])
    return rot.T @ (_closest(face, pose, c) - pose[:2])
