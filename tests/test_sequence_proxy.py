"""The push sequences' cheap ranking (:mod:`tooltransfer.planner.planning.oe.sequence_proxy`): the dynamic
programme's split of the path's segments among a face order, checked against every split."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest

from tooltransfer.planner.planning.oe.sequence_proxy import best_boundaries


def _one_end_at_a_time(cost: np.ndarray, order: tuple[int, ...]) -> tuple[tuple[int, ...], float]:
    """The dynamic programme as it was written before it took every end of a block at once (one end at a time):
    the reference the plans' bit-identity rests on (the same least start on ties, the same inf and NaN)."""
    k, p = cost.shape[0], len(order)
    if p > k:
        return (), np.inf
    cum = np.vstack([np.zeros((1, cost.shape[1])), np.cumsum(cost, axis=0)])
    best = np.full((p + 1, k + 1), np.inf)
    arg = np.zeros((p + 1, k + 1), dtype=int)
    best[0, 0] = 0.0
    for i in range(1, p + 1):
        f = order[i - 1]
        for e in range(i, k + 1):
            starts = np.arange(i - 1, e)
            with np.errstate(invalid="ignore"):
                vals = best[i - 1, starts] + cum[e, f] - cum[starts, f]
            j = int(np.argmin(vals))
            best[i, e], arg[i, e] = vals[j], starts[j]
    cuts, e = [], k
    for i in range(p, 0, -1):
        e = arg[i, e]
        cuts.append(e)
    return tuple(sorted(cuts)[1:]), float(best[p, k])


def _every_split(cost: np.ndarray, order: tuple[int, ...]) -> tuple[float, set[tuple[int, ...]]]:
    """The least cost of splitting the segments into ``len(order)`` non-empty consecutive blocks, and every
    split (block starts after the first) that attains it, by enumeration."""
    k, p = cost.shape[0], len(order)
    best, at = np.inf, set()
    for cuts in combinations(range(1, k), p - 1):
        edges = (0, *cuts, k)
        c = sum(float(cost[a:b, f].sum()) for a, b, f in zip(edges[:-1], edges[1:], order, strict=True))
        if c < best - 1e-12:
            best, at = c, {cuts}
        elif abs(c - best) <= 1e-12:
            at.add(cuts)
    return best, at


@pytest.mark.parametrize("seed", range(6))
def test_the_split_is_the_least_of_every_split(seed: int) -> None:
    """On random costs (ties among them on integer costs), the split found is one of the least-cost splits
    and its cost is theirs; more blocks than segments is no split at all."""
    rng = np.random.default_rng(seed)
    for _ in range(40):
        k, faces = int(rng.integers(1, 11)), int(rng.integers(1, 4))
        cost = rng.random((k, faces)) if seed % 2 else rng.integers(0, 3, (k, faces)).astype(float)
        for p in range(1, 5):
            order = tuple(int(f) for f in rng.integers(0, faces, p))
            cuts, c = best_boundaries(cost, order)
            if p > k:
                assert (cuts, c) == ((), np.inf)
                continue
            least, splits = _every_split(cost, order)
            assert c == pytest.approx(least, abs=1e-12)
            assert cuts in splits


def test_the_split_is_the_one_end_at_a_time_gave_bit_for_bit() -> None:
    """Against the dynamic programme taken one end at a time: the same split and the very same cost on random
    tables with ties, infinite and NaN costs, and from one segment to more blocks than segments."""
    rng = np.random.default_rng(7)
    for trial in range(800):
        k, faces = int(rng.integers(1, 16)), int(rng.integers(1, 4))
        cost = [rng.random((k, faces)), rng.integers(0, 3, (k, faces)).astype(float),
                np.where(rng.random((k, faces)) < 0.3, np.inf, rng.random((k, faces))),
                np.where(rng.random((k, faces)) < 0.1, np.nan, rng.random((k, faces)))][trial % 4]
        for p in range(1, 6):
            order = tuple(int(f) for f in rng.integers(0, faces, p))
            cuts, c = best_boundaries(cost, order)
            ref_cuts, ref_c = _one_end_at_a_time(cost, order)
            assert cuts == ref_cuts
            assert c == ref_c or (np.isnan(c) and np.isnan(ref_c))
