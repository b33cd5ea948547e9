"""The initial guess of the switch NLP's separating variables for a start path
(:mod:`tooltransfer.planner.planning.ss.nlp`).

The NLP starts from the path the ``opt`` variant is given; beside its knots it needs the separating variables
(:func:`initial_separators`): for a disc, the unit direction from its centre to the nearest point of the tool's
piece; for a polygon, the direction between the two centres with the offset half way between the projections.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.ss.bodies import Body
from tooltransfer.planner.planning.ss.nlp import SwitchNLP

__all__ = ["initial_separators"]


def initial_separators(nlp: SwitchNLP, xy_mm: NDArray[np.float64], yaw: NDArray[np.float64],
                       bodies: Sequence[Body]) -> NDArray[np.float64]:
    """Initial separating variables (n_sep, N - 2) for the path ``xy_mm`` (N, 2) [mm] / ``yaw`` (N,):
    for a disc, the unit direction from its centre to the nearest point of the piece; for a polygon,
    the direction between the centres with ``beta`` half way between the two shapes' projections."""
    N = nlp.n_knots
    out = np.zeros((nlp.n_sep, N - 2))
    if nlp.n_sep == 0:
        return out
    c, s = np.cos(yaw[1:-1]), np.sin(yaw[1:-1])
    R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (K, 2, 2)
    for j, bi, off, poly in nlp.sep_layout:
        w = np.einsum("kij,vj->kvi", R, nlp.pieces[j]) + xy_mm[1:-1, None, :]  # (K, V, 2)
        b = bodies[bi]
        if not poly:
            cen = b.data[:2]
            a, e = w, np.roll(w, -1, axis=1) - w
            t = np.clip(np.einsum("kvi,kvi->kv", cen - a, e) / np.maximum(np.einsum("kvi,kvi->kv", e, e), 1e-12), 0, 1)
            near = a + t[..., None] * e
            d = near - cen
            dist = np.hypot(d[..., 0], d[..., 1])
            best = d[np.arange(d.shape[0]), dist.argmin(axis=1)]
            # a centre inside the piece: point away from the piece's centroid
            inside = _inside_convex(w, cen)
            best[inside] = cen - w[inside].mean(axis=1)
            n = best / np.maximum(np.hypot(best[:, 0], best[:, 1]), 1e-12)[:, None]
            if nlp.angle:
                out[off] = np.arctan2(n[:, 1], n[:, 0])
            else:
                out[off:off + 2] = n.T
        else:
            ov = b.data.reshape(-1, 2)
            d = w.mean(axis=1) - ov.mean(axis=0)
            n = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]
            lo = np.einsum("kvi,ki->kv", w, n).min(axis=1)
            hi = (ov @ n.T).max(axis=0)
            if nlp.angle:
                out[off] = np.arctan2(n[:, 1], n[:, 0])
                out[off + 1] = 0.5 * (lo + hi)
            else:
                out[off:off + 2] = n.T
                out[off + 2] = 0.5 * (lo + hi)
    return out


def _inside_convex(w: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether ``p`` (2,) lies inside each convex polygon ``w`` (K, V, 2) (either orientation)."""
    e = np.roll(w, -1, axis=1) - w
    cr = e[..., 0] * (p[1] - w[..., 1]) - e[..., 1] * (p[0] - w[..., 0])
    return np.all(cr >= 0, axis=1) | np.all(cr <= 0, axis=1)
