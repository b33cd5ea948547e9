"""Cheap ranking of push sequences before any QP: which face could carry each stretch of the path.

The generalized universal path is cut into ``K`` equal time segments. For each segment and face,
``cost[k, f]`` estimates how far the path would have to move for that face to push it there: the
displacement its velocity makes outside the face's cone over the segment (the velocity's distance
to the cone, integrated in time) plus how far the path leaves the face's reach sector. A push
sequence is an order of faces (no face twice in a row) with switch times on segment boundaries;
for a given order, dynamic programming finds the boundaries of least total cost.
"""

from __future__ import annotations

from itertools import pairwise, product

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.constraints import reach_constraints
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.tools.pose import wrap_angle

Sequence_ = tuple[tuple[str, ...], tuple[int, ...], float]
"""(faces, switch segment boundaries (P-1,), proxy cost)."""


def cone_distance(v: NDArray[np.float64], phi: NDArray[np.float64], theta_b: float) -> NDArray[np.float64]:
    """Distance [m/s] (K,) from velocities ``v`` (K, 2) to the cones of half-angle ``theta_b`` about
    directions ``phi`` (K,) [rad]."""
    speed = np.linalg.norm(v, axis=1)
    ang = np.abs(wrap_angle(np.arctan2(v[:, 1], v[:, 0]) - phi))
    excess = np.maximum(ang - theta_b, 0.0)
    return np.where(excess >= np.pi / 2, speed, speed * np.sin(np.minimum(excess, np.pi / 2)))


def reach_distance(frame: FaceFrame, x: NDArray[np.float64]) -> NDArray[np.float64]:
    """How far [m] (K,) each point of ``x`` (K, 2) is outside ``frame``'s reach (0 inside)."""
    out = np.zeros(x.shape[0])
    for c in reach_constraints(frame):
        coeff = c.coefficients(np.arange(x.shape[0], dtype=np.float64), x)
        out = np.maximum(out, coeff.residuals(x, np.zeros_like(x)).max(axis=1))
    return out


def segment_costs(
    t: NDArray[np.float64], x: NDArray[np.float64], v: NDArray[np.float64], frames: list[FaceFrame], k: int
) -> NDArray[np.float64]:
    """``cost[k, f]`` [m^2] (K, F) for the path ``x``, ``v`` (T, 2) on times ``t`` (T,)."""
    bounds = np.linspace(t[0], t[-1], k + 1)
    seg = np.clip(np.searchsorted(bounds, t, side="right") - 1, 0, k - 1)
    dt = np.gradient(t)
    cost = np.zeros((k, len(frames)))
    for j, fr in enumerate(frames):
        off = cone_distance(v, fr.push_direction(x), fr.theta_b) * dt
        reach = reach_distance(fr, x)
        for s in range(k):
            m = seg == s
            cost[s, j] = off[m].sum() ** 2 + (reach[m].max() if m.any() else 0.0) ** 2
    return cost


def best_boundaries(cost: NDArray[np.float64], order: tuple[int, ...]) -> tuple[tuple[int, ...], float]:
    """Least-cost split of the K segments into ``len(order)`` non-empty consecutive blocks carried by
    faces ``order``; returns the block starts after the first (segment indices) and the cost."""
    k, p = cost.shape[0], len(order)
    if p > k:
        return (), np.inf
    cum = np.vstack([np.zeros((1, cost.shape[1])), np.cumsum(cost, axis=0)])
    best = np.full((p + 1, k + 1), np.inf)
    arg = np.zeros((p + 1, k + 1), dtype=int)
    best[0, 0] = 0.0
    ends = np.arange(k + 1)[:, None]
    for i in range(1, p + 1):
        f = order[i - 1]
        # every end e >= i at once: block i starts at s in [i - 1, e - 1] (the same sums, term by term, as one
        # end at a time; later starts masked, so the first least start is taken, as argmin over each end's starts)
        starts = np.arange(i - 1, k)
        with np.errstate(invalid="ignore"):  # inf - inf where a face cannot carry a stretch at all, as before
            vals = best[i - 1, starts][None, :] + cum[i:, f][:, None] - cum[starts, f][None, :]
        vals = np.where(starts[None, :] < ends[i:], vals, np.inf)
        j = np.argmin(vals, axis=1)
        best[i, i:], arg[i, i:] = vals[np.arange(len(j)), j], starts[j]
    cuts, e = [], k
    for i in range(p, 0, -1):
        e = arg[i, e]
        cuts.append(e)
    return tuple(sorted(cuts)[1:]), float(best[p, k])


def ranked_sequences(
    cost: NDArray[np.float64], names: list[str], max_pushes: int, price: float
) -> list[Sequence_]:
    """Every face order of at most ``max_pushes`` pushes (no face twice in a row) with its best
    boundaries, ranked by proxy cost plus ``price`` per face change."""
    out: list[Sequence_] = []
    f = len(names)
    for p in range(1, max_pushes + 1):
        for order in product(range(f), repeat=p):
            if any(a == b for a, b in pairwise(order)):
                continue
            cuts, c = best_boundaries(cost, order)
            if np.isfinite(c):
                out.append((tuple(names[i] for i in order), cuts, c + price * (p - 1)))
    out.sort(key=lambda s: s[2])
    return out
