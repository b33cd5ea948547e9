"""Where the puck can go from the start, face by face, when a switch needs a way for the tool round the puck.

The backward-reachable set (:mod:`.backward`) lets the pushing face change anywhere. Some tasks fail only
because the change they need is impossible: the tool, held by the Omni, cannot get from the contact pose of
one face to that of the other round the resting puck without meeting an obstacle, the puck or its joint
limits (:mod:`.switch_space`). Here each face ``f`` has its own set ``F_f`` of puck positions, grown from
the start on the blocks of :mod:`.backward` (block ``W``, face ``f``: its directions ``K_fW`` and where it
holds the puck ``S_fW``, :func:`~.backward.block_face`):

- ``F_f`` holds a disc of radius ``gap`` about the start for each face that may hold the puck there;
- push: each ``y`` of ``S_fW`` with some ``x`` of ``F_f`` in the closure of ``S_fW`` and ``y - x`` in
  ``K_fW`` is in ``F_f`` (the set grown by the cone, :func:`~.backward.shadow` with the arc turned by pi);
- switch: each point of ``F_g`` in ``S_fW`` is in ``F_f``, unless no switch from ``g`` to ``f`` exists
  for a puck anywhere in ``W`` (:func:`block_separated`). Re-contacts keep the face.

If the sets are closed and none comes within ``gap`` of the target's goal disc, no plan reaches the
target: cut the puck's path where the pushing face changes and into pieces shorter than ``h / 2``, each
in the block of the grid vertex nearest its first point (as :mod:`.backward`, read forward). The first
piece starts at the start, in ``F_f`` of its face; a push piece of ``f`` that starts in ``F_f`` ends in
it (its displacement, an integral of velocities in ``K_fW``, lies in ``K_fW``); where the face changes
from ``g`` to ``f`` at ``x`` the puck rests at ``x``, a contact of ``g`` and one of ``f`` both hold it
and the tool moves between them, so no block holding ``x`` has the pair separated: ``x``, in ``F_g``
and ``S_fW``, is in ``F_f``. So the path ends in some ``F_f``, away from the goal disc.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
import shapely

from tooltransfer.planner.planning.verdicts.backward import (
    BUDGET_SPENT,
    COARSEN,
    ROUNDING,
    BlockGrid,
    _clipped,
    _split,
    block_face,
    coarsen,
    face_regions,
    polygonal,
    safe_union,
    shadow,
)
from tooltransfer.planner.planning.verdicts.bounds import push_space
from tooltransfer.planner.planning.verdicts.rules import PushRules
from tooltransfer.planner.planning.verdicts.switch_space import PlacementSpace, components

#: Puck centres per side of a block at which the faces' contact poses are placed (each padded to the
#: rest of its share of the block: :meth:`~.switch_space.PlacementSpace.contact_places`).
BLOCK_SAMPLES = 3
#: Contact places per face and puck centre (their pads cover the places between).
BLOCK_CONTACTS = 24

Model = dict[str, tuple[tuple[float, float] | None, shapely.Geometry, shapely.Geometry]]


def block_separated(space: PlacementSpace, faces: list[str], box: tuple[float, float, float, float],
                    radius: float) -> frozenset[tuple[str, str]]:
    """The pairs ``(g, f)`` of ``faces`` between which no switch exists with the puck (``radius`` [m]) at
    rest anywhere in ``box`` [m]: the free placements with the puck shrunk by the box's half-diagonal about
    its middle (they hold those of every puck in the box) leave the contact poses of ``g`` (for every puck
    in the box: :data:`BLOCK_SAMPLES` centres per side, each padded to its share) and those of ``f`` in
    different components; also every pair with a face none of whose contact poses is free there."""
    x0, y0, x1, y1 = box
    middle = np.array([0.5 * (x0 + x1), 0.5 * (y0 + y1)])
    rows = space.free_rows(middle, radius, spread=0.5 * math.hypot(x1 - x0, y1 - y0))
    labels = components(rows)
    cell = ((x1 - x0) / BLOCK_SAMPLES, (y1 - y0) / BLOCK_SAMPLES)
    share = 0.5 * math.hypot(*cell)
    centres = [np.array([x0 + (i + 0.5) * cell[0], y0 + (j + 0.5) * cell[1]])
               for i in range(BLOCK_SAMPLES) for j in range(BLOCK_SAMPLES)]
    held: dict[str, set[int]] = {}
    for name in faces:
        face, got = space.tool.face(name), set()
        for c in centres:
            places = space.contact_places(face, c, radius, BLOCK_CONTACTS, spread=share)
            got |= space.place_components(places, rows, labels)
        held[name] = got
    return frozenset((g, f) for g in faces for f in faces if g != f and not (held[g] & held[f]))


@dataclass
class ForwardResult:
    """What :func:`forward_sets` found: the closed sets ``regions`` per face (None when the work stopped
    early), why it stopped early ("" when it finished), the block updates made and the grid."""

    regions: dict[str, shapely.Geometry] | None
    stopped: str
    blocks_processed: int
    grid: BlockGrid


class _Blocks:
    """The faces' models and separated pairs per block, made once each."""

    def __init__(self, rules: PushRules, space: PlacementSpace, zone: shapely.Geometry) -> None:
        self.rules, self.space, self.zone = rules, space, zone
        self.regions = face_regions(rules)
        self.models: dict[tuple[float, ...], Model] = {}
        self.seps: dict[tuple[float, ...], frozenset[tuple[str, str]]] = {}

    def model(self, box: tuple[float, float, float, float]) -> Model:
        if box not in self.models:
            out = {}
            for rule, region in zip(self.rules.faces, self.regions, strict=True):
                m = block_face(self.rules, rule, region, box, self.zone)
                if m is not None:
                    out[rule.name] = m
            self.models[box] = out
        return self.models[box]

    def separated(self, box: tuple[float, float, float, float]) -> frozenset[tuple[str, str]]:
        if box not in self.seps:
            self.seps[box] = block_separated(self.space, [r.name for r in self.rules.faces], box, self.rules.radius)
        return self.seps[box]

    def grown(self, box: tuple[float, float, float, float], own: dict[str, shapely.Geometry]
              ) -> dict[str, shapely.Geometry]:
        """Per face, the points of ``box`` its set must hold given the sets' parts ``own`` there (module
        docstring: its pushes from its own set, switches from the others' where not separated)."""
        out = {}
        for f, (arc, sp, near) in self.model(box).items():
            parts = []
            src = polygonal(shapely.intersection(own[f], near))
            if not src.is_empty:
                turned = None if arc is None else (arc[0] + math.pi, arc[1] + math.pi)
                parts.append(shapely.intersection(shadow(src, turned, box), sp))
            others = [g for g in own if g != f and not own[g].is_empty]
            if others:
                cut = self.separated(box)
                # within S_fW grown by the rounding, as the pushes' sources are: a set that only touches S_fW
                # still passes. Not the set grown: two faces switched freely would hand each other a set grown
                # by the rounding at every update, a growth that builds up without end where a push's edge
                # meets an obstacle's zone at a narrow angle (benchmarks/README.md, twenty-first session)
                parts += [polygonal(shapely.intersection(own[g], near)) for g in others if (g, f) not in cut]
            grown = polygonal(safe_union(parts)) if parts else shapely.Polygon()
            if not grown.is_empty:
                out[f] = grown
        return out


def forward_sets(rules: PushRules, space: PlacementSpace, grid: BlockGrid, start: np.ndarray,
                 goal: shapely.Geometry, holders: list[str], *, gap: float, max_blocks: int,
                 zone: shapely.Geometry, exact: bool = False) -> ForwardResult:
    """The smallest closed sets (module docstring) on ``grid``, grown from a disc of radius ``gap`` [m] about
    ``start`` (2,) in the sets of the faces ``holders`` that may hold the puck there; stops early once a set
    comes within ``gap`` of the ``goal`` disc, or after ``max_blocks`` block updates. ``zone``: where the
    puck's centre may not be. Two passes, as :func:`~.backward.backward_set`: coarse pieces, then exact.
    ``exact``: the first pass stores its pieces as they are too (only its stopping tolerance is coarse), since
    the growth of :func:`~.backward.coarsen` at each update of a cell builds up where the sets run along an
    obstacle's zone (benchmarks/README.md, twentieth session); slower where the sets are large."""
    blocks = _Blocks(rules, space, zone)
    disc = shapely.Point(start).buffer(gap, quad_segs=16)
    cells: dict[str, dict[tuple[int, int], shapely.Geometry]] = {f.name: {} for f in rules.faces}
    for f in holders:
        cells[f] = _split(grid, disc)
    done = 0
    for tol, simplify in ((2 * COARSEN, not exact), (ROUNDING, False)):
        stopped, done = _close(blocks, grid, cells, goal, gap, max_blocks, done, tol, simplify)
        if stopped:
            return ForwardResult(None, stopped, done, grid)
        if simplify:  # back inside their cells, so that a block grows from all of a set in it
            cells = {f: _clipped(grid, per) for f, per in cells.items()}
    return ForwardResult({f: safe_union(list(c.values())) if c else shapely.Polygon() for f, c in cells.items()},
                         "", done, grid)


def _close(blocks: _Blocks, grid: BlockGrid, cells: dict[str, dict[tuple[int, int], shapely.Geometry]],
           goal: shapely.Geometry, gap: float, max_blocks: int, done: int, tol: float, simplify: bool
           ) -> tuple[str, int]:
    """Grow ``cells`` (per face) block by block until no block adds more than ``tol`` [m] to any; returns
    why it stopped early ("" if it did not) and the block updates made so far."""
    nx, ny = grid.shape
    gx, gy = goal.centroid.x, goal.centroid.y

    def priority(c: tuple[int, int]) -> float:
        """Blocks nearer the goal first: a set reaches it sooner when the task is feasible."""
        x0, y0, x1, y1 = grid.block_box(*c)
        return math.hypot(max(x0 - gx, 0.0, gx - x1), max(y0 - gy, 0.0, gy - y1))

    queued = {(i + di, j + dj) for per in cells.values() for i, j in per for di in (0, 1) for dj in (0, 1)}
    heap = [(priority(c), c) for c in queued]
    heapq.heapify(heap)
    while heap:
        if done >= max_blocks:
            return f"{BUDGET_SPENT} {max_blocks} block updates", done
        _, (i, j) = heapq.heappop(heap)
        queued.discard((i, j))
        done += 1
        quad = ((i - 1, j - 1), (i - 1, j), (i, j - 1), (i, j))
        own = {f: safe_union([per[c] for c in quad if c in per]) for f, per in cells.items()}
        if all(g.is_empty for g in own.values()):
            continue
        box = grid.block_box(i, j)
        for f, grown in blocks.grown(box, own).items():
            for c in quad:
                if not (0 <= c[0] < nx and 0 <= c[1] < ny):
                    continue
                piece = polygonal(shapely.intersection(grown, shapely.box(*grid.cell_box(*c))))
                old = cells[f].get(c)
                if piece.is_empty or (old is not None
                                      and shapely.difference(piece, shapely.buffer(old, tol)).area <= 0):
                    continue
                union = piece if old is None else safe_union([old, piece])
                cells[f][c] = coarsen(union) if simplify else polygonal(union)
                if shapely.distance(cells[f][c], goal) <= gap:
                    return "a set came within the gap of the target", done
                for nb in ((c[0] + di, c[1] + dj) for di in (0, 1) for dj in (0, 1)):
                    if nb not in queued:
                        queued.add(nb)
                        heapq.heappush(heap, (priority(nb), nb))
    return "", done


def check_forward(rules: PushRules, space: PlacementSpace, grid: BlockGrid,
                  regions: dict[str, shapely.Geometry], start: np.ndarray, goal: shapely.Geometry,
                  holders: list[str], gap: float, zone: shapely.Geometry) -> list[str]:
    """What is wrong with the closed sets ``regions`` (module docstring; empty: nothing), checked again
    block by block with the faces' models and the separated pairs made anew: the grid covers the push
    space, the goal and the start, each holder's set holds the start's disc, none comes within ``gap`` of the
    ``goal``, no block adds area to any set."""
    problems = []
    disc = shapely.Point(start).buffer(0.5 * gap, quad_segs=16)
    if set(regions) != {f.name for f in rules.faces}:
        return ["the sets are not the faces'"]
    x0, y0 = grid.block_box(0, 0)[:2]
    x1, y1 = grid.block_box(*grid.shape)[2:]
    if not shapely.covers(shapely.box(x0, y0, x1, y1), shapely.union_all([push_space(rules), goal, disc])):
        return ["the grid does not cover the push space, the goal and the start"]
    for f in holders:
        if not shapely.covers(shapely.buffer(regions[f], 1e-9), disc):
            problems.append(f"the set of {f!r} does not hold the start")
    if any(shapely.distance(g, goal) <= gap for g in regions.values() if not g.is_empty):
        problems.append("a set comes within the gap of the target")
    blocks = _Blocks(rules, space, zone)
    for i, j in grid.blocks():
        box = grid.block_box(i, j)
        own = {f: shapely.intersection(g, shapely.box(*box)) for f, g in regions.items()}
        if all(g.is_empty or g.area == 0.0 for g in own.values()):
            continue
        for f, grown in blocks.grown(box, own).items():
            missing = shapely.difference(grown, shapely.buffer(regions[f], 1e-8))
            if missing.area > 1e-14:
                problems.append(f"block {(i, j)} is not closed for {f!r} ({missing.area * 1e6:.3g} mm^2 outside)")
                return problems
    return problems
