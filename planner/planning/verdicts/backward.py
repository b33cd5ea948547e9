"""The set of puck positions from which the target may be reachable, over-approximated on blocks.

Cover the plane with square cells of side ``h`` and call *block* the 2 x 2 cells around a grid vertex.
For each block ``W`` and face ``f`` let ``K_fW`` be a convex cone holding every direction ``f`` may push
the puck in at a point of ``W`` (its cone turned by the headings there:
:func:`~tooltransfer.planner.planning.verdicts.bounds.face_headings`) and ``S_fW`` a set holding every
position of ``W`` where ``f`` can hold the puck (its region, less the obstacles' zone and less where
its tool body overlaps an obstacle whatever the contact). A set ``B`` is *closed* when, for every
block and face, each ``x`` of ``S_fW`` with some ``y`` of ``B`` in the closure of ``S_fW`` and
``y - x`` in ``K_fW`` is in ``B``. If ``B`` is closed and holds the target's goal disc, every start from
which a plan reaches the target is in ``B``:

    cut the puck's path where the pushing face changes and into pieces shorter than ``h / 2``; each
    piece is pushed by one face ``f`` and lies in the block of the grid vertex nearest its first
    point (at least ``h / 2`` from that block's edges), all its points in ``S_fW`` (the face holds
    the puck there), and its displacement, the integral of velocities in ``K_fW``, lies in ``K_fW``;
    so going backward from the last piece, which ends in the goal disc, each piece's first point is
    in ``B``. Between pushes the puck stands still.

:func:`backward_set` computes such a ``B`` on polygons (the shadow of ``B`` in a block is
``(B ∩ W) ⊕ (-K_fW)``, a Minkowski sum swept edge by edge, kept in ``S_fW``), block by block from a
work list, until no block adds area. The work stops early, without a set, once ``B`` comes within
``gap`` of the start, or when it has processed ``max_blocks`` blocks.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely
import shapely.errors

from tooltransfer.planner.planning.verdicts.bounds import body_zone, face_headings, face_region, obstacle_zone
from tooltransfer.planner.planning.verdicts.rules import FaceRule, PushRules

#: Cones wider than this [rad] are taken as the whole plane (the swept triangle would be too long).
WIDEST_CONE = 0.9 * math.pi
#: Two polygons closer than this [m] count as touching (floating-point rounding of shapely's
#: operations; well below the start's required gap).
ROUNDING = 1e-9


#: A block's faces from its box (:func:`block_faces`' list: each face's directions, hold set and that grown).
BlockModel = Callable[[tuple[float, float, float, float]], list]

#: How :attr:`BackwardResult.stopped` begins when the work ran out of block updates (a larger budget may
#: still close the set: :func:`tooltransfer.planner.planning.verdicts.decide.budget_limited` looks for it).
BUDGET_SPENT = "budget:"

#: Precision grid [m] of the set operations (GEOS's snap-rounding overlay, robust where floating-point
#: overlay may fail on nearly parallel edges).
GRID = 1e-10


@dataclass(frozen=True)
class BlockGrid:
    """The cells and blocks of :mod:`backward`.

    Attributes:
        origin: shape (2,), the lower-left corner of cell (0, 0) [m].
        h: cell side [m].
        shape: ``(nx, ny)`` cells.
    """

    origin: tuple[float, float]
    h: float
    shape: tuple[int, int]

    def cell_box(self, i: int, j: int) -> tuple[float, float, float, float]:
        """The box ``(x0, y0, x1, y1)`` [m] of cell ``(i, j)``."""
        x0, y0 = self.origin[0] + i * self.h, self.origin[1] + j * self.h
        return x0, y0, x0 + self.h, y0 + self.h

    def block_box(self, i: int, j: int) -> tuple[float, float, float, float]:
        """The box [m] of the block about grid vertex ``(i, j)`` (cells ``i - 1..i``, ``j - 1..j``)."""
        x, y = self.origin[0] + i * self.h, self.origin[1] + j * self.h
        return x - self.h, y - self.h, x + self.h, y + self.h

    def blocks(self) -> list[tuple[int, int]]:
        """Every grid vertex ``(i, j)``, ``0 <= i <= nx``, ``0 <= j <= ny``."""
        return [(i, j) for i in range(self.shape[0] + 1) for j in range(self.shape[1] + 1)]

    def covered(self) -> shapely.Geometry:
        """The box [m] every block of the grid covers."""
        return shapely.box(*self.block_box(0, 0)[:2], *self.block_box(*self.shape)[2:])

    def to_dict(self) -> dict[str, object]:
        """JSON data."""
        return {"origin": list(self.origin), "h": self.h, "shape": list(self.shape)}


def unclosed_block(region: shapely.Geometry, grid: BlockGrid, model: BlockModel
                   ) -> tuple[tuple[int, int], float] | None:
    """The first block of ``grid`` where ``region`` is not closed under the faces ``model`` gives it (a push
    from its part there ends outside it by more than the rounding), with the area [m^2] outside; None: none."""
    for i, j in grid.blocks():
        box = grid.block_box(i, j)
        own = shapely.intersection(region, shapely.box(*box))
        if own.is_empty or own.area == 0.0:
            continue
        missing = shapely.difference(grow(own, model(box), box), shapely.buffer(region, 1e-8))
        if missing.area > 1e-14:
            return (i, j), float(missing.area)
    return None


def grid_over(area: shapely.Geometry, h: float) -> BlockGrid:
    """A :class:`BlockGrid` of cell side ``h`` [m] covering ``area`` with one cell to spare each side."""
    x0, y0, x1, y1 = area.bounds
    ox, oy = math.floor(x0 / h) * h - h, math.floor(y0 / h) * h - h
    return BlockGrid((ox, oy), h, (math.ceil((x1 - ox) / h) + 1, math.ceil((y1 - oy) / h) + 1))


def block_faces(rules: PushRules, box: tuple[float, float, float, float], zone: shapely.Geometry,
                regions: list[shapely.Geometry]
                ) -> list[tuple[tuple[float, float] | None, shapely.Geometry, shapely.Geometry]]:
    """For each face that can push somewhere in the block ``box`` [m], its :func:`block_face`."""
    out = [block_face(rules, rule, region, box, zone) for rule, region in zip(rules.faces, regions, strict=True)]
    return [m for m in out if m is not None]


def block_face(rules: PushRules, rule: FaceRule, region: shapely.Geometry, box: tuple[float, float, float, float],
               zone: shapely.Geometry) -> tuple[tuple[float, float] | None, shapely.Geometry, shapely.Geometry] | None:
    """Face ``rule`` (its ``region``) in the block ``box`` [m]: its directions there (an arc ``(lo, hi)``
    [rad], None for every direction), where in the box it can hold the puck (its region less the obstacles'
    ``zone`` and less where its tool body overlaps an obstacle), and that set grown by :data:`ROUNDING`
    (prepared: the set's pieces it touches are taken from it); None where it cannot push in the box."""
    rect = shapely.box(*box)
    hd = face_headings(rules, rule, box)
    if hd is False:
        return None
    sp = shapely.difference(shapely.intersection(region, rect), zone)
    if hd is not None:
        sp = shapely.difference(sp, body_zone(rules, rule, hd))
    sp = polygonal(sp)
    if sp.is_empty:
        return None
    arc = None if hd is None else (hd[0] + rule.cone[0], hd[1] + rule.cone[1])
    near = shapely.buffer(sp, ROUNDING)
    shapely.prepare(near)
    return None if arc is None or arc[1] - arc[0] > WIDEST_CONE else arc, sp, near


def face_regions(rules: PushRules) -> list[shapely.Geometry]:
    """Every face's region (:func:`~tooltransfer.planner.planning.verdicts.bounds.face_region`), in order."""
    return [face_region(rules, f) for f in rules.faces]


def grow(own: shapely.Geometry, faces: list, box: tuple[float, float, float, float]
         ) -> shapely.Geometry:
    """The points of the block ``box`` from which one push ends in ``own`` (the set's part in the
    block): per face, the shadow of ``own`` within the face's space, kept in that space."""
    parts = []
    for arc, sp, near in faces:
        src = polygonal(shapely.intersection(own, near))
        if src.is_empty:
            continue
        parts.append(shapely.intersection(shadow(src, arc, box), sp))
    return polygonal(safe_union(parts)) if parts else shapely.Polygon()


#: Outward growth [m] of a stored piece before it is simplified (bounds its vertex count).
COARSEN = 2e-5


def coarsen(g: shapely.Geometry) -> shapely.Geometry:
    """A polygon holding ``g`` with fewer vertices: ``g`` grown by :data:`COARSEN` (mitred), then
    simplified within half of that (every point of ``g`` stays inside)."""
    return polygonal(shapely.simplify(shapely.buffer(polygonal(g), COARSEN, join_style="mitre"), 0.5 * COARSEN))


def safe_union(geoms: list[shapely.Geometry]) -> shapely.Geometry:
    """The union of ``geoms``; where floating-point overlay fails on nearly coincident edges, GEOS's
    snap-rounding overlay on the :data:`GRID` (moves no point by more than that)."""
    try:
        return shapely.union_all(geoms)
    except shapely.errors.GEOSException:
        return shapely.buffer(shapely.union_all(geoms, grid_size=GRID), GRID, join_style="mitre")


def polygonal(g: shapely.Geometry) -> shapely.Geometry:
    """The polygons of ``g`` (made valid; lines and points that set operations leave are dropped)."""
    if shapely.get_type_id(g) in (3, 6) and shapely.is_valid(g):  # already polygons: as they are
        return g if g.area > 0.0 else shapely.Polygon()
    parts = shapely.get_parts(shapely.get_parts(shapely.make_valid(g)))
    polys = [p for p in parts if shapely.get_type_id(p) == 3 and p.area > 0.0]
    return shapely.union_all(polys) if polys else shapely.Polygon()


def shadow(piece: shapely.Geometry, cone: tuple[float, float] | None, box: tuple[float, float, float, float]
           ) -> shapely.Geometry:
    """``(piece ⊕ (-K)) ∩ box`` [m]: the points of ``box`` from which a displacement in the cone ``K``
    (arc ``cone`` [rad]; None: every direction) reaches ``piece`` (in ``box``).

    The sum with the cone's triangle ``T`` is ``piece`` and the sums ``e ⊕ T`` of its edges through
    which a point of ``piece`` leaves along ``-K`` (outward normal ``n`` with ``n · t > 0`` for some
    ``t`` of ``T``): a point ``p + t`` outside ``piece`` is reached by leaving it through such an edge."""
    rect = shapely.box(*box)
    piece = polygonal(piece)
    if piece.is_empty:
        return shapely.Polygon()
    if cone is None:
        return rect
    lo, hi = cone
    reach = math.hypot(box[2] - box[0], box[3] - box[1]) / math.cos(0.5 * (hi - lo)) * 1.01
    t = -reach * np.array([[math.cos(lo), math.sin(lo)], [math.cos(hi), math.sin(hi)]])
    edges = []
    for ring in shapely.get_rings(shapely.get_parts(shapely.normalize(piece))):
        c = shapely.get_coordinates(ring)
        e = np.stack([c[:-1], c[1:]], axis=1)
        d = e[:, 1] - e[:, 0]
        # normalize() orients shells clockwise and holes counter-clockwise: the outward normal of a
        # clockwise edge d is (-d_y, d_x), and so is that of a counter-clockwise hole's edge
        n = np.column_stack([-d[:, 1], d[:, 0]])
        keep = (n @ t.T > 0).any(axis=1)
        edges.append(e[keep] if keep.any() else e[:0])
    seg = np.concatenate(edges) if edges else np.zeros((0, 2, 2))
    if not len(seg):
        return polygonal(shapely.intersection(piece, rect))
    pts = np.concatenate([seg, seg[:, [0]] + t[None], seg[:, [1]] + t[None]], axis=1)  # (m, 6, 2)
    hulls = shapely.convex_hull(shapely.multipoints(pts.reshape(-1, 2), indices=np.repeat(np.arange(len(seg)), 6)))
    hulls = hulls[(shapely.get_type_id(hulls) == 3) & (shapely.area(hulls) > 0.0)]
    return polygonal(shapely.intersection(safe_union([piece, *hulls]), rect))


@dataclass
class BackwardResult:
    """What :func:`backward_set` found.

    Attributes:
        region: the closed set ``B`` [m] (None when the work stopped early).
        stopped: why the work stopped early ("" when it finished): the start reached, or the budget.
        blocks_processed: block updates made.
        grid: the blocks used.
    """

    region: shapely.Geometry | None
    stopped: str
    blocks_processed: int
    grid: BlockGrid


def backward_set(rules: PushRules, space: shapely.Geometry, goal: shapely.Geometry, start: np.ndarray, *,
                 h: float = 0.01, gap: float = 5e-4, max_blocks: int = 20000,
                 zone: shapely.Geometry | None = None, exact: bool = False,
                 max_vertices: int | None = None, model: BlockModel | None = None) -> BackwardResult:
    """The smallest closed set (module docstring) holding ``goal`` [m], grown inside ``space`` (the
    push space, :func:`~tooltransfer.planner.planning.verdicts.bounds.push_space`), on blocks of cells of side
    ``h`` [m]; stops early once it comes within ``gap`` [m] of ``start`` (2,). ``zone``: where no path
    from the start goes (default: the obstacles' zone; a larger one, such as the far side of a quantity no
    push decreases, :func:`~tooltransfer.planner.planning.verdicts.spiral.start_side`, keeps the argument
    sound: every piece of such a path lies outside it).

    Two passes: a coarse one whose pieces are grown by :data:`COARSEN` and simplified (few vertices,
    quick), then an exact one from the coarse set until no block adds area beyond the rounding. ``exact``:
    the coarse pass stores its pieces as they are too (only its stopping tolerance is coarse): the growth
    at each update of a cell builds up, and on a task at the edge of the rules it alone takes the set to
    the start (benchmarks/README.md, twenty-first session); slower where the set is large, and where exact
    pieces gather vertices (on one task tens of thousands in one block) each update costs more: ``max_vertices``
    bounds the work, the vertices of the pieces grown summed over the updates (None: no bound). ``model``: each
    block's faces (as :func:`block_faces` gives them) in another plane than the world's (the plane of
    ``space``, ``goal`` and ``start``, :mod:`.polar_sets`; its faces keep out of its own zone, and ``zone`` is not
    used); None: the world's, :func:`block_faces`."""
    grid = grid_over(shapely.union(space, goal), h)
    if model is None:
        world_zone, regions = obstacle_zone(rules) if zone is None else zone, face_regions(rules)
        model = lambda box: block_faces(rules, box, world_zone, regions)  # noqa: E731
    models: dict[tuple[int, int], list] = {}
    cells = _split(grid, goal)
    done, work = 0, _Vertices(max_vertices)
    for tol, simplify in ((2 * COARSEN, not exact), (ROUNDING, False)):
        cells, stopped, done = _close(model, grid, cells, start, gap, max_blocks, done, models, tol, simplify, work)
        if stopped:
            return BackwardResult(None, stopped, done, grid)
        if simplify:  # the coarse pieces back inside their cells, so that a block grows from all of the set in it
            cells = _clipped(grid, cells)
    return BackwardResult(safe_union(list(cells.values())), "", done, grid)


Cells = dict[tuple[int, int], shapely.Geometry]


@dataclass
class _Vertices:
    """The vertices of the pieces grown so far over both passes of :func:`backward_set`, and their bound
    (None: none)."""

    bound: int | None
    grown: int = 0


def _clipped(grid: BlockGrid, cells: Cells) -> Cells:
    """Each cell's piece cut to the cell (a coarsened piece may reach :data:`COARSEN` over its edges, into
    blocks that do not grow from it); empty pieces dropped. Only over-approximation is cut: the exact pass
    then closes the set again."""
    out = {}
    for c, g in cells.items():
        piece = polygonal(shapely.intersection(g, shapely.box(*grid.cell_box(*c))))
        if not piece.is_empty:
            out[c] = piece
    return out


def _split(grid: BlockGrid, g: shapely.Geometry) -> dict[tuple[int, int], shapely.Geometry]:
    """``g`` cut into the grid's cells (only the cells its bounds meet: the others hold none of it)."""
    x0, y0, x1, y1 = g.bounds
    ox, oy, h = grid.origin[0], grid.origin[1], grid.h
    out = {}
    for i in range(max(0, math.floor((x0 - ox) / h)), min(grid.shape[0], math.floor((x1 - ox) / h) + 1)):
        for j in range(max(0, math.floor((y0 - oy) / h)), min(grid.shape[1], math.floor((y1 - oy) / h) + 1)):
            piece = polygonal(shapely.intersection(g, shapely.box(*grid.cell_box(i, j))))
            if not piece.is_empty:
                out[(i, j)] = piece
    return out


def _close(model: BlockModel, grid: BlockGrid, cells: dict, start: np.ndarray, gap: float, max_blocks: int,
           done: int, models: dict, tol: float, simplify: bool, work: _Vertices) -> tuple[dict, str, int]:
    """Grow ``cells`` block by block (each block's faces from ``model``) until no block adds more than ``tol``
    [m] beyond them; returns the cells, why it stopped early ("" if it did not) and the block updates made so
    far. ``work``: the vertices grown so far and their bound, updated here."""
    nx, ny = grid.shape
    start_pt = shapely.Point(start)
    sx, sy = (float(v) for v in start)

    def priority(c: tuple[int, int]) -> float:
        """Blocks nearer the start first: the set reaches it sooner when the task is feasible."""
        x0, y0, x1, y1 = grid.block_box(*c)
        return math.hypot(max(x0 - sx, 0.0, sx - x1), max(y0 - sy, 0.0, sy - y1))

    queued = {(i + di, j + dj) for i, j in cells for di in (0, 1) for dj in (0, 1)}
    heap = [(priority(c), c) for c in queued]
    heapq.heapify(heap)
    while heap:
        if done >= max_blocks:
            return cells, f"{BUDGET_SPENT} {max_blocks} block updates", done
        _, v = heapq.heappop(heap)
        queued.discard(v)
        done += 1
        i, j = v
        quad = ((i - 1, j - 1), (i - 1, j), (i, j - 1), (i, j))
        own = [cells[c] for c in quad if c in cells]
        if not own:
            continue
        box = grid.block_box(i, j)
        if v not in models:
            models[v] = model(box)
        source = safe_union(own)
        work.grown += shapely.get_num_coordinates(source)
        if work.bound is not None and work.grown > work.bound:
            return cells, f"{BUDGET_SPENT} {work.bound} vertices grown", done
        grown = grow(source, models[v], box)
        for c in quad:
            if grown.is_empty or not (0 <= c[0] < nx and 0 <= c[1] < ny):
                continue
            piece = polygonal(shapely.intersection(grown, shapely.box(*grid.cell_box(*c))))
            if piece.is_empty:
                continue
            old = cells.get(c)
            if old is not None and shapely.difference(piece, shapely.buffer(old, tol)).area <= 0.0:
                continue
            union = piece if old is None else safe_union([old, piece])
            cells[c] = coarsen(union) if simplify else polygonal(union)
            if shapely.distance(cells[c], start_pt) <= gap:
                return cells, "the set came within the gap of the start", done
            for nb in ((c[0] + di, c[1] + dj) for di in (0, 1) for dj in (0, 1)):
                if nb not in queued:
                    queued.add(nb)
                    heapq.heappush(heap, (priority(nb), nb))
    return cells, "", done
