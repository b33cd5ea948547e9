"""The rows of one interior knot of the switch NLP, as CasADi SX expressions
(:mod:`tooltransfer.planner.planning.ss.nlp`).

The tool enters as its convex pieces or as a capsule (:class:`Capsule`), in millimetres in the tool frame
(:class:`ToolRows`); at an interior knot its centre is a variable and its heading a function of that centre
through the Omni's waist (:class:`InteriorKnot`). :func:`body_rows` gives the non-penetration rows of one body
against the tool (signed distance to a disc, separating lines, or the capsule's clamped distance) and
:func:`reach_rows` the Omni's reach rows; every row is ``>= 0`` when satisfied. The forms and why they are
chosen are in the NLP module's docstring. The NLP derives these rows once for one knot and maps them over the
knots (:mod:`tooltransfer.planner.planning.ss.knot_rows`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.ss.bodies import UNIT, Body
from tooltransfer.tools.model import Tool
from tooltransfer.tools.omni.heading import heading_casadi
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.omni.reach import reach_sector, wedge_rows

__all__ = ["Capsule", "InteriorKnot", "ToolRows", "body_rows", "reach_families", "reach_rows"]


@dataclass(frozen=True)
class Capsule:
    """A capsule tool model in the tool frame: segment ``a``-``b`` (2,) [m] grown by ``radius`` [m]."""

    a: NDArray[np.float64]
    b: NDArray[np.float64]
    radius: float

    @staticmethod
    def enclosing(tool: Tool, n_grid: int = 13) -> Capsule:
        """The capsule of least area covering every outline vertex among those whose segment lies on the
        tool frame's vertical line through the middle of the outline's width, with each end inset from
        the outline's extent by a fraction of its half width (a grid of ``n_grid`` insets per end)."""
        v = np.asarray(tool.outline.exterior.coords, dtype=np.float64)[:-1]
        x0 = 0.5 * (v[:, 0].min() + v[:, 0].max())
        half = 0.5 * (v[:, 0].max() - v[:, 0].min())
        best: Capsule | None = None
        best_area = np.inf
        for lo in np.linspace(0.0, half, n_grid):
            for hi in np.linspace(0.0, half, n_grid):
                a, b = np.array([x0, v[:, 1].min() + lo]), np.array([x0, v[:, 1].max() - hi])
                ab = b - a
                t = np.clip(((v - a) @ ab) / max(float(ab @ ab), 1e-18), 0.0, 1.0)
                r = float(np.max(np.hypot(*(v - a - t[:, None] * ab).T)))
                area = 2.0 * r * float(np.hypot(*ab)) + np.pi * r * r
                if area < best_area:
                    best, best_area = Capsule(a, b, r), area
        assert best is not None
        return best


def reach_families(reach: bool | tuple[bool, bool, bool]) -> tuple[bool, bool, bool]:
    """``(inner circle, outer circle, waist wedge)`` reach rows to build: all for True, none for False."""
    if isinstance(reach, bool):
        return (reach, reach, reach)
    inner, outer, wedge = (bool(v) for v in reach)
    return inner, outer, wedge


@dataclass(frozen=True)
class ToolRows:
    """How the tool enters the non-penetration rows: its model, convex ``pieces`` [mm] (tool
    frame) or ``capsule`` [mm], and the separators: their form (``angle``, or ``distance`` for the
    signed-distance rows of discs), the per-knot ``(piece, body, offset, has_beta)`` layout and
    the count ``n_sep`` of separating variables per interior knot."""

    model: str
    pieces: list[NDArray[np.float64]]
    capsule: Capsule | None
    angle: bool
    distance: bool
    sep_layout: list[tuple[int, int, int, bool]]
    n_sep: int

    @classmethod
    def of(cls, tool: Tool, bodies: Sequence[Body], model: str, separators: str) -> ToolRows:
        """The tool's pieces (or capsule) in millimetres and the separating variables each pair of
        piece and body needs (none for a disc under ``"distance"``)."""
        angle = separators == "angle"
        pieces = [np.asarray(p.exterior.coords, dtype=np.float64)[:-1] / UNIT for p in tool.convex_pieces]
        capsule = None
        if model == "capsule":
            c = Capsule.enclosing(tool)
            capsule = Capsule(c.a / UNIT, c.b / UNIT, c.radius / UNIT)
        sep_layout: list[tuple[int, int, int, bool]] = []
        n_sep = 0
        distance = separators == "distance"
        if model == "pieces":
            for j in range(len(pieces)):
                for bi, b in enumerate(bodies):
                    poly = b.kind == "poly"
                    if distance and not poly:
                        continue  # the signed distance row needs no separating variables
                    sep_layout.append((j, bi, n_sep, poly))
                    n_sep += (1 if angle else 2) + (1 if poly else 0)
        return cls(model, pieces, capsule, angle, distance, sep_layout, n_sep)


class InteriorKnot:
    """The tool at one interior knot (SX): its centre ``Xi, Yi`` [mm] and the heading's cosine and
    sine (the heading a function of position through the Omni's waist)."""

    def __init__(self, centre: Any, platform: OmniPlatform) -> None:
        import casadi as ca

        self.Xi, self.Yi = centre[0], centre[1]
        yaw = heading_casadi(platform, self.Xi * UNIT, self.Yi * UNIT)
        self.cos_k, self.sin_k = ca.cos(yaw), ca.sin(yaw)

    def world(self, v: NDArray[np.float64]) -> tuple[Any, Any]:
        """The tool-frame point ``v`` (2,) [mm] in the world at the knot."""
        return self.Xi + self.cos_k * v[0] - self.sin_k * v[1], self.Yi + self.sin_k * v[0] + self.cos_k * v[1]

    def tool_frame(self, cx: Any, cy: Any) -> tuple[Any, Any]:
        """The world point ``(cx, cy)`` in the tool frame at the knot (there the tool's outline is
        constant, so distance expressions and their Hessians stay small)."""
        rx, ry = cx - self.Xi, cy - self.Yi
        return self.cos_k * rx + self.sin_k * ry, self.cos_k * ry - self.sin_k * rx


def body_rows(knots: InteriorKnot, tr: ToolRows, b: Body, bi: int, p: Any, m: Any, S: Any) -> list[Any]:
    """Non-penetration rows (SX scalars of one knot, each >= 0) of body ``b`` (number ``bi``, parameters ``p``,
    margin row ``m`` [mm]) against the tool: the capsule's distance, the signed distance of each
    piece to a disc, or the separating-line rows of each piece (separating variables ``S``)."""
    import casadi as ca

    per_knot: list[Any] = []
    if tr.model == "capsule":
        assert tr.capsule is not None
        lx, ly = knots.tool_frame(p[0], p[1])
        d2 = _clamped_d2(lx, ly, tr.capsule.a, tr.capsule.b - tr.capsule.a)
        per_knot.append(ca.sqrt(d2) - (p[2] + tr.capsule.radius + m))
    elif tr.distance and b.kind == "disc":
        lx, ly = knots.tool_frame(p[0], p[1])
        for verts in tr.pieces:
            per_knot.append(_signed_distance(verts, lx, ly) - (p[2] + m))
    else:
        for j, verts in enumerate(tr.pieces):
            off = next(o for (jj, bb, o, _) in tr.sep_layout if jj == j and bb == bi)
            if tr.angle:
                n0, n1 = ca.cos(S[off, :]), ca.sin(S[off, :])
                beta = S[off + 1, :] if b.kind == "poly" else None
            else:
                n0, n1 = S[off, :], S[off + 1, :]
                beta = S[off + 2, :] if b.kind == "poly" else None
            for v in verts:
                wx, wy = knots.world(v)
                if b.kind == "disc":
                    per_knot.append(n0 * (wx - p[0]) + n1 * (wy - p[1]) - (p[2] + m))
                else:
                    per_knot.append(n0 * wx + n1 * wy - beta - m)
            if b.kind == "poly":
                for vi in range(b.data.size // 2):
                    per_knot.append(beta - (n0 * p[2 * vi] + n1 * p[2 * vi + 1]))
            if not tr.angle:
                per_knot.append(1 - n0 * n0 - n1 * n1)
    return per_knot


def reach_rows(knots: InteriorKnot, platform: OmniPlatform, reach: bool | tuple[bool, bool, bool],
                reach_margin: float) -> list[Any]:
    """Reach rows (SX scalars of one knot, each >= 0, scaled to millimetres): inside the
    outer radius, outside the inner one and inside the wedge's two half-planes, each
    ``reach_margin`` [m] inside, as far as :func:`reach_families` keeps them."""
    sec = reach_sector(platform)
    wr = wedge_rows(platform)
    bx0, by0 = sec.centre / UNIT
    r_in, r_out = (sec.r_in + reach_margin) / UNIT, (sec.r_out - reach_margin) / UNIT
    Xi, Yi = knots.Xi, knots.Yi
    inner, outer, wedge = reach_families(reach)
    r2 = (Xi - bx0) ** 2 + (Yi - by0) ** 2
    per_knot = []
    if inner:
        per_knot.append((r2 - r_in**2) / r_in)
    if outer:
        per_knot.append((r_out**2 - r2) / r_out)
    for gi in range(2 if wedge else 0):
        per_knot.append(wr.h[gi] / UNIT - reach_margin / UNIT - (wr.G[gi, 0] * Xi + wr.G[gi, 1] * Yi))
    return per_knot


def _signed_distance(verts: NDArray[np.float64], lx: Any, ly: Any) -> Any:
    """Signed distance [mm] from the point ``(lx, ly)`` (in the tool frame, [mm]) to the convex piece
    with vertices ``verts`` (V, 2) [mm]: outside, the least clamped point-to-edge distance (exact,
    continuously differentiable); inside, the largest signed distance to the edges' lines
    (negative). In the tool frame the edges are constants, so the expression (and its Hessian) stays
    small."""
    import casadi as ca

    v = np.asarray(verts, dtype=np.float64)
    if _area2(v) < 0:
        v = v[::-1]
    d2: Any = None  # the least squared distance to an edge so far (CasADi expression)
    line: Any = None  # the largest signed distance to an edge's line so far
    for i in range(len(v)):
        a, e = v[i], v[(i + 1) % len(v)] - v[i]
        di = _clamped_d2(lx, ly, a, e)
        li = ((lx - a[0]) * e[1] - (ly - a[1]) * e[0]) / np.sqrt(float(e @ e))  # to the edge's line, + outside
        d2 = di if d2 is None else ca.fmin(d2, di)
        line = li if line is None else ca.fmax(line, li)
    return ca.if_else(line > 0, ca.sqrt(d2 + 1e-12), line)


def _clamped_d2(lx: Any, ly: Any, a: NDArray[np.float64], e: NDArray[np.float64]) -> Any:
    """Squared distance [mm^2] from ``(lx, ly)`` to the constant segment from ``a`` along ``e`` (2,) [mm]
    (the clamped point-to-segment distance)."""
    import casadi as ca

    rx, ry = lx - a[0], ly - a[1]
    t = ca.fmin(1, ca.fmax(0, (rx * e[0] + ry * e[1]) / float(e @ e)))
    dx, dy = rx - t * e[0], ry - t * e[1]
    return dx * dx + dy * dy


def _area2(v: NDArray[np.float64]) -> float:
    """Twice the signed area of the polygon ``v`` (V, 2) (positive when counter-clockwise)."""
    return float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))
