"""Finding a demonstration's contacts: the forward strokes of each face, then when each stroke's contact starts
and ends (:mod:`tooltransfer.planner.learning.segmentation.core`, steps 1-4).

A stroke runs from where a face's normal velocity turns positive to its farthest advance before it falls back;
its contact starts where the tool's outline reaches the object's rest position and ends midway through the
stall at the farthest advance. Contacts of one face close in time are merged into one.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.learning.segmentation.tracks import Tracks, pose_at

__all__ = ["Contact", "face_strokes", "find_contacts", "merge_contacts"]


def face_strokes(v: NDArray[np.float64], near: NDArray[np.bool_], dt: float, v_on: float, min_advance: float,
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


Contact = tuple[int, float, float, NDArray[np.float64], NDArray[np.float64]]
"""A contact found: face index, start and end [s], rest before (2,) [m], tool pose at its end (1, 3)."""


def merge_contacts(found: list[Contact], gap: float) -> list[Contact]:
    """Consecutive contacts of one face less than ``gap`` [s] apart joined into one."""
    merged: list[Contact] = []
    for f in found:
        if merged and merged[-1][0] == f[0] and f[1] - merged[-1][2] < gap:
            merged[-1] = (f[0], merged[-1][1], f[2], merged[-1][3], f[4])
        else:
            merged.append(f)
    return merged


def find_contacts(tr: Tracks, strokes: list[tuple[int, int, int]], *, near_tol: float, end_tol: float, face_tol: float,
              settle: float) -> list[Contact]:
    """Pass 1, in time order: the contacts of the ``strokes`` (first, last sample, face index);
    each rest lasts from one contact's end to the next one's start (module docstring, steps 2-3)."""
    t, t_o, obj, v_n = tr.t, tr.t_o, tr.obj, tr.v_n
    found: list[Contact] = []
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
        end_pose = pose_at(t, tr.pose, t_top)
        found.append((j, t_start, t_end, before, end_pose))
        prev_end, prev_pose, prev_face = t_end, end_pose, j
    return found
