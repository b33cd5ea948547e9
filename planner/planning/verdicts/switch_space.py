"""Where the tool can be while the puck rests, and which of those places one move of the tool joins.

A switch (or a re-contact) moves the tool, the puck at rest, from the contact pose of one face to that
of another, in the table plane, within the Omni's joints, without penetrating the obstacles or the puck
(docs/design.md 11). On the Omni the tool's placement in the plane is fixed by two numbers: the waist
angle ``a = base_yaw + q1`` and the arm-plane reach ``u``. Its frame's origin is ``b + R(a) (u, d_t)``
and its heading ``a - pi/2`` (:mod:`tooltransfer.tools.omni.reach`); the joints allow the box
``q1_range x u_range``. So a switch is a path in that box through the placements where the tool is
free, and where the two contact poses lie in different connected pieces of the free placements, no
switch joins them, whatever path a planner tries.

:class:`PlacementSpace` over-approximates the free placements on rows of the waist angle:

- row ``k`` holds every ``a`` within ``dq / 2`` of its middle ``a_k``. Turning the tool about the
  Omni's axis by at most ``dq / 2`` moves each of its points by at most ``delta = r_max dq / 2``
  (``r_max``: the farthest any tool point comes from the axis). So where the tool placed at ``(a_k, u)``
  meets an obstacle shrunk by ``delta``, it meets the obstacle itself at every ``a`` of the row: the
  row is *blocked* at ``u``;
- along a row the tool slides along the direction ``(cos a_k, sin a_k)`` as ``u`` varies, so the
  blocked ``u`` of one convex piece of the outline and one convex obstacle is one interval, where that
  line cuts their Minkowski difference (computed exactly from the vertices). Discs are replaced by
  inscribed polygons (a smaller obstacle: fewer blocked placements) and the puck, a disc, is exact. The
  puck is shrunk by ``delta`` too and, for a puck anywhere within ``spread`` of a point, by ``spread``;
- the rest of a row, its *free intervals*, holds every free placement of the row. Two free intervals
  of neighbouring rows are joined where they overlap (a path that crosses from one row to the next does
  so at one ``u`` in both).

So the placements of one connected piece of the true free space lie in one *component* of the free
intervals: where every contact pose of one face and every contact pose of another lie in different
components, no switch between them exists (:meth:`PlacementSpace.separated`). Checked against brute
force (the outline placed on a fine grid, shapely) and against the switch paths of solved plans in
``tests/test_switch_space.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.planner.planning.setting import Setting
from tooltransfer.tools.model import Face, Tool
from tooltransfer.tools.objects import Disc, Obstacle
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.omni.reach import reach_sector

#: The farthest [m] a tool point moves as the waist turns across one row (:attr:`PlacementSpace.delta`).
ROW_MOVE = 2e-4
#: Vertices of the polygons inscribed in disc obstacles.
DISC_SIDES = 64
#: Contact places sampled along a face's contact range (:meth:`PlacementSpace.contact_components`).
CONTACT_SAMPLES = 64

Intervals = list[tuple[float, float]]


def _ccw_hull(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """The convex hull's vertices (n, 2), counter-clockwise."""
    hull = shapely.orient_polygons(shapely.convex_hull(shapely.multipoints(points)))
    if shapely.get_type_id(hull) != 3:  # degenerate (a segment or a point): nothing to block
        return np.zeros((0, 2))
    return np.asarray(hull.exterior.coords)[:-1]


def _line_cut(hull: NDArray[np.float64], e: NDArray[np.float64]) -> tuple[float, float] | None:
    """``(lo, hi)``: the ``u`` with ``u e`` in the convex polygon ``hull`` (n, 2) counter-clockwise, or None."""
    if len(hull) < 3:
        return None
    d = np.roll(hull, -1, axis=0) - hull
    normal = np.column_stack([d[:, 1], -d[:, 0]])  # outward for a counter-clockwise ring
    h = np.einsum("ij,ij->i", normal, hull)
    ne = normal @ e
    flat = np.abs(ne) < 1e-15
    if np.any(flat & (h < 0.0)):
        return None
    lo = float(np.max(h[ne < 0] / ne[ne < 0], initial=-np.inf))
    hi = float(np.min(h[ne > 0] / ne[ne > 0], initial=np.inf))
    return (lo, hi) if lo <= hi else None


def _free(blocked: Intervals, lo: float, hi: float) -> Intervals:
    """``[lo, hi]`` less the union of the ``blocked`` intervals."""
    out, at = [], lo
    for a, b in sorted(blocked):
        if b < at or a > hi:
            continue
        if a > at:
            out.append((at, a))
        at = max(at, b)
    if at < hi:
        out.append((at, hi))
    return out


def _convex_parts(o: Obstacle, shrink: float) -> list[NDArray[np.float64]]:
    """Convex polygons (vertices) inside obstacle ``o`` shrunk by ``shrink`` [m]: a disc's inscribed polygon,
    a polygon's triangles each shrunk (their union lies inside the shrunk polygon)."""
    if isinstance(o, Disc):
        r = o.radius - shrink
        return [] if r <= 0 else [np.asarray(shapely.Point(o.centre).buffer(r, quad_segs=DISC_SIDES // 4)
                                             .exterior.coords)[:-1]]
    pieces = [o] if abs(o.convex_hull.area - o.area) <= 1e-12 * max(o.area, 1e-12) else \
        list(shapely.get_parts(shapely.constrained_delaunay_triangles(o)))
    out = []
    for p in pieces:
        small = p.buffer(-shrink, join_style="mitre") if shrink > 0 else p
        if not small.is_empty and shapely.get_type_id(small) == 3:
            out.append(np.asarray(small.exterior.coords)[:-1])
    return out


@dataclass(eq=False)
class PlacementSpace:
    """The tool's placements ``(a, u)`` on the Omni with the obstacles in place (module docstring).

    Attributes:
        tool, platform: the tool and the Omni holding it.
        obstacles: the obstacles (discs and polygons) [m].
        dq: row width [rad]; ``delta`` [m]: how far a tool point moves across a row.
    """

    tool: Tool
    platform: OmniPlatform
    obstacles: list[Obstacle]
    dq: float = 0.0
    delta: float = field(init=False)

    def __post_init__(self) -> None:
        sec = reach_sector(self.platform)
        self.base, self.base_yaw = np.asarray(sec.centre, dtype=np.float64), float(sec.base_yaw)
        self.q1_range, self.u_range = sec.q1_range, sec.u_range
        self.pieces = [np.asarray(p.exterior.coords)[:-1] for p in self.tool.convex_pieces]
        reach = max(float(np.hypot(*v.T).max()) for v in self.pieces)
        r_max = math.hypot(self.u_range[1] + reach, abs(D_TOOL) + reach)
        self.dq = self.dq or ROW_MOVE / r_max
        self.delta = r_max * self.dq / 2
        self.n_rows = math.ceil((self.q1_range[1] - self.q1_range[0]) / self.dq)
        walls = [v for o in self.obstacles for v in _convex_parts(o, self.delta)]
        self.walls = [self._row_cuts(k, walls) for k in range(self.n_rows)]

    def row_angle(self, k: int) -> float:
        """The waist angle ``a`` [rad] at the middle of row ``k``."""
        return self.base_yaw + self.q1_range[0] + (k + 0.5) * self.dq

    def _placed(self, a: float) -> tuple[list[NDArray[np.float64]], NDArray[np.float64]]:
        """The outline's convex pieces placed at ``(a, 0)`` and the direction ``u`` slides them in."""
        yaw = a - math.pi / 2
        rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
        e = np.array([math.cos(a), math.sin(a)])
        origin = self.base + D_TOOL * np.array([-math.sin(a), math.cos(a)])
        return [v @ rot.T + origin for v in self.pieces], e

    def _row_cuts(self, k: int, walls: list[NDArray[np.float64]]) -> Intervals:
        """The ``u`` of row ``k`` where a piece of the tool meets one of the convex ``walls``."""
        placed, e = self._placed(self.row_angle(k))
        cuts = [_line_cut(_ccw_hull((w[:, None, :] - p[None, :, :]).reshape(-1, 2)), e) for p in placed for w in walls]
        return [c for c in cuts if c is not None]

    def _puck_cuts(self, centre: NDArray[np.float64], radius: float) -> list[Intervals]:
        """Per row, the ``u`` where a piece of the tool meets the disc (``centre`` (2,), ``radius``) [m]:
        where the line ``centre - u e`` comes within ``radius`` of the piece (its vertices' circles and its
        edges moved out by ``radius``), exact and vectorised over the rows."""
        a = self.row_angle(0) + self.dq * np.arange(self.n_rows)
        yaw = a - math.pi / 2
        c, s = np.cos(yaw), np.sin(yaw)
        origin = self.base[None] + D_TOOL * np.column_stack([-np.sin(a), np.cos(a)])
        e = np.column_stack([np.cos(a), np.sin(a)])
        out: list[Intervals] = [[] for _ in range(self.n_rows)]
        for v in self.pieces:
            p = np.stack([v[:, 0] * c[:, None] - v[:, 1] * s[:, None],
                          v[:, 0] * s[:, None] + v[:, 1] * c[:, None]], axis=2) + origin[:, None, :]
            w = centre[None, None, :] - p
            we = np.einsum("kni,ki->kn", w, e)
            disc = we ** 2 - np.einsum("kni,kni->kn", w, w) + radius ** 2
            root = np.sqrt(np.maximum(disc, 0.0))
            lo = np.where(disc >= 0, we - root, np.inf).min(axis=1)
            hi = np.where(disc >= 0, we + root, -np.inf).max(axis=1)
            d = np.roll(p, -1, axis=1) - p
            ccw = 0.5 * np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]) > 0
            n = (1.0 if ccw else -1.0) * np.stack([d[..., 1], -d[..., 0]], axis=2)
            n /= np.linalg.norm(n, axis=2, keepdims=True)
            rhs = centre[None, None, :] - (p + radius * n)  # centre - u e = p + radius n + t d
            det = e[:, None, 0] * d[..., 1] - e[:, None, 1] * d[..., 0]
            ok = np.abs(det) > 1e-15
            det = np.where(ok, det, 1.0)
            u = (rhs[..., 0] * d[..., 1] - rhs[..., 1] * d[..., 0]) / det
            t = (e[:, None, 0] * rhs[..., 1] - e[:, None, 1] * rhs[..., 0]) / det
            hit = ok & (t >= 0.0) & (t <= 1.0)
            lo = np.minimum(lo, np.where(hit, u, np.inf).min(axis=1))
            hi = np.maximum(hi, np.where(hit, u, -np.inf).max(axis=1))
            for k in np.flatnonzero(lo <= hi):
                out[k].append((float(lo[k]), float(hi[k])))
        return out

    def free_rows(self, centre: NDArray[np.float64], radius: float, spread: float = 0.0) -> list[Intervals]:
        """Each row's free intervals of ``u`` [m] with the puck (``radius`` [m]) at ``centre`` (2,) [m], or
        anywhere within ``spread`` [m] of it: the puck shrunk by ``spread`` and ``delta``."""
        shrunk = radius - spread - self.delta
        puck = self._puck_cuts(np.asarray(centre, dtype=np.float64), shrunk) if shrunk > 0 else \
            [[] for _ in range(self.n_rows)]
        return [_free(self.walls[k] + puck[k], *self.u_range) for k in range(self.n_rows)]

    def contact_places(self, face: Face, centre: NDArray[np.float64], radius: float, n: int = CONTACT_SAMPLES,
                       spread: float = 0.0) -> list[tuple[float, float, float, float]]:
        """``(q1, u, pad_q1, pad_u)`` of ``n`` contact poses of ``face`` along its contact range holding the puck
        (``radius`` [m]) at ``centre`` (2,) [m]: the waist ``q1`` [rad] and reach ``u`` [m] (the pose
        ``p = b + R(a) (u + c_y, d_t - c_x)`` of :mod:`tooltransfer.planner.planning.verdicts.rules`, the arm
        reaching forward) and how far [rad, m] a contact between this sample and the next can be from it
        (``|da/do| = 1/v``, ``|du/do| = |o|/v``, ``|du/dc_y| = 1``; ``o``, ``c_y`` move at most the face's
        length per unit of its fraction), and for a puck anywhere within ``spread`` [m] of ``centre``
        (``|da/dp| <= 1/|d| + |o| / (|d| v)``, ``|du/dp| = |d|/v``, ``d = p - b``), each bound taken at the
        smallest ``|d|`` and ``v`` and the largest ``|o|`` there (infinite pads where those bounds fail: the
        pose may then be anywhere). Poses outside the joints by more than that are left out."""
        d = np.asarray(centre, dtype=np.float64) - self.base
        r2 = float(d @ d)
        near = math.sqrt(r2) - spread  # the least |d| within the spread
        s = np.linspace(face.contact_range[0], face.contact_range[1], n)
        step = face.length * (s[1] - s[0]) / 2 if n > 1 else 0.0
        out = []
        for si in s:
            c = face.point(float(si)) + radius * face.normal
            o = D_TOOL - float(c[0])
            v2_lo = near * abs(near) - (abs(o) + step) ** 2
            if r2 <= o * o:
                continue  # the puck too near the Omni's axis for this contact: no pose at all
            v = math.sqrt(r2 - o * o)
            u = v - float(c[1])
            q1 = math.remainder(math.atan2(d[1], d[0]) - math.atan2(o, v) - self.base_yaw, 2 * math.pi)
            if near <= 0.0 or v2_lo <= 0.0:  # no bound on how far the pose moves: it may be anywhere
                out.append((q1, u, math.inf, math.inf))
                continue
            v_lo = math.sqrt(v2_lo)
            pad_q = step / v_lo + spread * (1.0 + (abs(o) + step) / v_lo) / near
            pad_u = step * (1.0 + (abs(o) + step) / v_lo) + spread * (near + 2.0 * spread) / v_lo
            if (self.q1_range[0] - pad_q <= q1 <= self.q1_range[1] + pad_q
                    and self.u_range[0] - pad_u <= u <= self.u_range[1] + pad_u):
                out.append((q1, u, pad_q, pad_u))
        return out

    def contact_components(self, face: Face, centre: NDArray[np.float64], radius: float, rows: list[Intervals],
                           labels: list[list[int]]) -> set[int]:
        """The components (:func:`components` of ``rows``, ``labels``) that any contact pose of ``face``
        holding the puck at ``centre`` (2,) [m] can lie in (:meth:`place_components`)."""
        return self.place_components(self.contact_places(face, centre, radius), rows, labels)

    def place_components(self, places: list[tuple[float, float, float, float]], rows: list[Intervals],
                         labels: list[list[int]]) -> set[int]:
        """The components any of ``places`` (:meth:`contact_places`) can lie in: every free interval within a
        place's pads of it, in every row its waist may fall in."""
        out: set[int] = set()
        for q1, u, pad_q, pad_u in places:
            if math.isinf(pad_q) or math.isinf(pad_u):
                out.update(lab for row in labels for lab in row)
                continue
            k0 = max(0, math.floor((q1 - pad_q - self.q1_range[0]) / self.dq))
            k1 = min(self.n_rows - 1, math.floor((q1 + pad_q - self.q1_range[0]) / self.dq))
            for k in range(k0, k1 + 1):
                out.update(lab for (lo, hi), lab in zip(rows[k], labels[k], strict=True)
                           if lo <= u + pad_u and hi >= u - pad_u)
        return out

    def separated(self, face_a: Face, face_b: Face, centre: NDArray[np.float64], radius: float,
                  spread: float = 0.0) -> bool:
        """Whether no move of the tool joins a contact pose of ``face_a`` to one of ``face_b`` with the puck
        (``radius`` [m]) at rest at ``centre`` (2,) [m], or anywhere within ``spread`` [m] of it (module
        docstring: their components differ; the contact poses for the centre only, a caller with a
        ``spread`` pads them itself). False where either face has no contact pose there."""
        rows = self.free_rows(centre, radius, spread)
        labels = components(rows)
        a = self.contact_components(face_a, centre, radius, rows, labels)
        b = self.contact_components(face_b, centre, radius, rows, labels)
        return bool(a) and bool(b) and not (a & b)


def components(rows: list[Intervals]) -> list[list[int]]:
    """A label per free interval of each row: intervals of neighbouring rows that overlap (closed) share
    one, and so, transitively, do all the intervals of one component."""
    parent: list[int] = []
    ids: list[list[int]] = []
    for row in rows:
        ids.append(list(range(len(parent), len(parent) + len(row))))
        parent += ids[-1]

    def root(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for k in range(len(rows) - 1):
        here, there = rows[k], rows[k + 1]
        i = j = 0
        while i < len(here) and j < len(there):
            if here[i][1] >= there[j][0] and there[j][1] >= here[i][0]:
                parent[root(ids[k][i])] = root(ids[k + 1][j])
            if here[i][1] < there[j][1]:
                i += 1
            else:
                j += 1
    return [[root(x) for x in row] for row in ids]


def placement_space(setting: Setting) -> PlacementSpace:
    """The :class:`PlacementSpace` of a planning world (its tool, platform and obstacles)."""
    return PlacementSpace(setting.tool, setting.platform, list(setting.obstacles))
