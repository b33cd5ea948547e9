"""The push sequences' cheap ranking (:mod:`tooltransfer.planner.planning.oe.sequence_proxy`): the dynamic
programme's split of the path's segments among a face order, checked against every split."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest

from tooltransfer.planner.planning.oe.sequence_proxy import best_boundaries


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
