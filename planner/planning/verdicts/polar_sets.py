"""The positions reachable from the start that could still reach the target, on blocks of log-polar cells.

About the Omni's axis take ``U = r0 ln(r / r0)`` and ``V = r0 (phi - phi0)`` (``r``, ``phi``: the puck's
distance and polar angle; ``r0``, ``phi0``: the target's). The map is conformal, so a push's direction in
the ``(U, V)`` plane is its world direction less ``phi``; with face ``f`` that is the face's cone turned by
``-asin(o / r) - pi/2`` (:mod:`.spiral`), which depends on ``r`` alone. On blocks of this plane a face's cone
therefore spreads only by how ``asin(o / r)`` changes over the block's distances, not by the polar angles
the block spans, which on the world's square blocks turn it by ``2 h / r`` (about 1.4 degrees on 2.5 mm cells at
0.2 m): where a push's edge passes an obstacle's margin by a fraction of a millimetre, only the former leaves
it out (``verd200-00147``: the cone's edge from the start runs 0.24 mm into the margin).

Two closed sets of :mod:`.backward`'s construction, built in that plane:

- ``B``: closed backward, holding the target's goal disc, on coarse cells (:data:`BACK_CELL`): every position
  from which a plan reaches the target is in ``B``, and so is every point of such a plan's path (each point's
  remaining path is a plan from it).
- ``F``: closed forward (every face's cone turned by ``pi``), holding a disc about the start, on fine cells
  (:data:`FORWARD_CELL`), each face held only within ``B``: cut a plan's path into pieces as :mod:`.backward`
  does; every piece lies in ``B`` and starts in ``F``, so it ends in ``F``.

If ``F`` leaves the target's goal disc out, no plan from the start reaches the target.

``F`` is first grown without ``B`` (that is, with ``B`` the whole push space, trivially closed backward), for
at most :data:`FORWARD_FIRST` updates: where it reaches the goal there, ``B`` (the costly set: some 20 s on a
wide push space) is not built, since a set ``F`` so quickly at the goal is rarely cut off from it by the coarse
``B`` (every task ``B`` has helped to certify, ``verd200-00147`` of the verdict benchmark and ``small-00002``,
``-00004`` and ``tiny-00003`` (seed 11) of the test batches, takes more than 3000 updates without it); where
it closes without reaching it, it is the certificate, with ``B`` the whole push space. Over-approximation
only: the obstacles' zone and the tool-body zone are drawn with inscribed polygons and their images shrunk by
:data:`IMAGE_ROOM`, the regions and the goal disc are taken larger, so each set holds what its exact
counterpart holds. The sets are stored in the ``(U, V)`` plane with ``r0`` and ``phi0``; their world image is
for drawing only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
import shapely.errors

from tooltransfer.planner.planning.verdicts.backward import (
    BUDGET_SPENT,
    ROUNDING,
    WIDEST_CONE,
    BackwardResult,
    BlockGrid,
    backward_set,
    grid_over,
    polygonal,
    unclosed_block,
)
from tooltransfer.planner.planning.verdicts.bounds import (
    body_zone,
    face_region,
    obstacle_zone,
    offset_turns,
    polar_ranges,
)
from tooltransfer.planner.planning.verdicts.rules import PushRules

#: Cell side [m of the (U, V) plane] of the backward set ``B`` (coarse: it only bounds where ``F`` grows).
BACK_CELL = 0.02
#: Cell side of the forward set ``F``.
FORWARD_CELL = 0.00125
#: Block updates of ``B`` and of ``F`` (each times the budget): ``verd200-00147`` takes 1799 in all.
BACK_BLOCKS = 3000
FORWARD_BLOCKS = 8000
#: Block updates of ``F`` grown first without ``B`` (module docstring; not scaled by the budget, so that a larger
#: budget builds ``B`` wherever a smaller one did).
FORWARD_FIRST = 1000
#: Radius [m] of the disc about the start that ``F`` holds, and the least distance it keeps from the target's
#: goal disc.
START_DISC = 5e-5
#: Length [m] of the world edges of a polygon before it is mapped: its mapped edges are chords of the mapped
#: curves, some 4e-7 m from them at most (sampled) for puck distances of 0.03 m and more and ``r0`` up to
#: 0.3 m (1.6e-6 m with edges of 0.2 mm; ``tests/test_polar_sets.py`` samples it).
DENSE = 1e-4
#: How far [m] mapped zones are shrunk and the mapped goal grown: above the chords' sagitta, far below any cell.
IMAGE_ROOM = 2e-6


@dataclass(frozen=True)
class LogPolar:
    """The map ``(x, y) -> (U, V)`` of the module docstring about ``base`` (2,) [m], with ``r0`` [m] and
    ``phi0`` [rad] (the polar angle is taken within half a turn of ``phi0``: the push space is a sector
    narrower than a turn)."""

    base: tuple[float, float]
    r0: float
    phi0: float

    @classmethod
    def about(cls, rules: PushRules, target: np.ndarray) -> LogPolar:
        """The map about the Omni's axis with the ``target`` (2,) [m] at the origin."""
        d = np.asarray(target, dtype=np.float64) - np.asarray(rules.base)
        return cls(rules.base, float(math.hypot(*d)), float(math.atan2(d[1], d[0])))

    def forward(self, xy: np.ndarray) -> np.ndarray:
        """``(U, V)`` (K, 2) [m] of the world points ``xy`` (K, 2) [m] (not the axis)."""
        d = np.atleast_2d(np.asarray(xy, dtype=np.float64)) - np.asarray(self.base)
        r = np.hypot(d[:, 0], d[:, 1])
        phi = np.remainder(np.arctan2(d[:, 1], d[:, 0]) - self.phi0 + math.pi, 2 * math.pi) - math.pi
        return np.column_stack([self.r0 * np.log(r / self.r0), self.r0 * phi])

    def inverse(self, uv: np.ndarray) -> np.ndarray:
        """The world points (K, 2) [m] of ``uv`` (K, 2)."""
        uv = np.atleast_2d(np.asarray(uv, dtype=np.float64))
        r, phi = self.r0 * np.exp(uv[:, 0] / self.r0), self.phi0 + uv[:, 1] / self.r0
        return np.asarray(self.base) + np.column_stack([r * np.cos(phi), r * np.sin(phi)])

    def polar(self, box: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
        """``(r_lo, r_hi, phi_lo, phi_hi)`` [m, rad] of the block ``box`` of the (U, V) plane."""
        u0, v0, u1, v1 = box
        return (self.r0 * math.exp(u0 / self.r0), self.r0 * math.exp(u1 / self.r0),
                self.phi0 + v0 / self.r0, self.phi0 + v1 / self.r0)

    def image(self, g: shapely.Geometry, room: float) -> shapely.Geometry:
        """The polygons ``g`` [m] mapped (edges cut to :data:`DENSE` first), then grown by ``room`` [m]
        (negative: shrunk)."""
        mapped = _mapped(g, self.forward)
        return mapped if mapped.is_empty else polygonal(shapely.buffer(mapped, room, join_style="mitre"))

    def world_sector(self, box: tuple[float, float, float, float]) -> shapely.Geometry:
        """A world polygon [m] holding the points of the block ``box`` (an annular sector, outer arc
        circumscribed, grown by 0.1 mm)."""
        r_lo, r_hi, p_lo, p_hi = self.polar(box)
        n = max(4, math.ceil((p_hi - p_lo) * r_hi / DENSE))
        a = np.linspace(p_lo, p_hi, n + 1)
        outer = np.column_stack([np.cos(a), np.sin(a)]) * (r_hi / math.cos(0.5 * (p_hi - p_lo) / n))
        inner = np.column_stack([np.cos(a[::-1]), np.sin(a[::-1])]) * r_lo
        return shapely.buffer(shapely.Polygon(np.vstack([outer, inner]) + np.asarray(self.base)), 1e-4)

    def to_dict(self) -> dict[str, Any]:
        """JSON data."""
        return {"r0": self.r0, "phi0": self.phi0}


@dataclass(frozen=True)
class PolarWorld:
    """The rules' sets in the (U, V) plane: each face's region (a box: its distances and polar angles), the
    obstacles' zone (shrunk image) and the push space."""

    map: LogPolar
    regions: tuple[shapely.Geometry, ...]
    zone: shapely.Geometry
    space: shapely.Geometry

    @classmethod
    def of(cls, rules: PushRules, lp: LogPolar) -> PolarWorld:
        """The sets of ``rules`` mapped by ``lp``."""
        regions = []
        for f in rules.faces:
            r_lo, r_hi, psi_lo, psi_hi = polar_ranges(f)
            lo, hi = rules.waist[0] + psi_lo, rules.waist[1] + psi_hi
            regions.append(shapely.box(lp.r0 * math.log(r_lo / lp.r0), lp.r0 * (lo - lp.phi0),
                                       lp.r0 * math.log(r_hi / lp.r0), lp.r0 * (hi - lp.phi0)))
        # the zone within the faces' regions (a sector narrower than a turn, where the polar angle is continuous)
        sector = shapely.buffer(shapely.union_all([face_region(rules, f) for f in rules.faces]), 1e-3)
        zone = lp.image(shapely.intersection(obstacle_zone(rules), sector), -IMAGE_ROOM)
        return cls(lp, tuple(regions), zone, shapely.difference(shapely.union_all(regions), zone))

    def block_faces(self, rules: PushRules, box: tuple[float, float, float, float], *, reverse: bool = False,
                    within: shapely.Geometry | None = None) -> list[tuple[tuple[float, float] | None, shapely.Geometry,
                                                                          shapely.Geometry]]:
        """Each face that can push in the block ``box`` of the plane: its directions there (an arc [rad] of the
        plane, turned by ``pi`` where ``reverse``; None: every direction), where in the box it can hold the puck
        (its region less the zone and the tool body's zone, within ``within`` where given) and that grown by
        the rounding (as :func:`~.backward.block_faces` gives them)."""
        r_lo, r_hi, p_lo, p_hi = self.map.polar(box)
        rect = shapely.box(*box)
        out = []
        for rule, region in zip(rules.faces, self.regions, strict=True):
            f_lo, f_hi, _, _ = polar_ranges(rule)
            lo_r, hi_r = max(r_lo, f_lo), min(r_hi, f_hi)
            if lo_r > hi_r:
                continue
            sp = shapely.difference(shapely.intersection(region, rect), self.zone)
            if within is not None:
                sp = shapely.intersection(sp, within)
            if sp.is_empty:
                continue
            least, largest = offset_turns(rule, lo_r, hi_r)
            if rule.core:  # the tool body at every heading the block allows (world), mapped
                body = shapely.intersection(body_zone(rules, rule, (p_lo - largest - math.pi / 2,
                                                                    p_hi - least - math.pi / 2)),
                                            self.map.world_sector(box))
                if not body.is_empty:
                    sp = shapely.difference(sp, self.map.image(body, -IMAGE_ROOM))
            sp = polygonal(sp)
            if sp.is_empty:
                continue
            turn = math.pi if reverse else 0.0
            arc = (rule.cone[0] - largest - math.pi / 2 + turn, rule.cone[1] - least - math.pi / 2 + turn)
            near = shapely.buffer(sp, ROUNDING)
            shapely.prepare(near)
            out.append((None if arc[1] - arc[0] > WIDEST_CONE else arc, sp, near))
        return out


@dataclass(frozen=True)
class BothWays:
    """What :func:`both_ways` found: the sets ``back`` (B) and ``ahead`` (F) of the (U, V) plane (None where
    the work stopped first), their grids, why it stopped ("" where both closed) and the block updates."""

    world: PolarWorld
    back: shapely.Geometry | None
    back_grid: BlockGrid | None
    ahead: shapely.Geometry | None
    ahead_grid: BlockGrid | None
    stopped: str
    blocks: int


def start_disc(lp: LogPolar, start: np.ndarray) -> shapely.Geometry:
    """The image of a polygon holding the disc of :data:`START_DISC` about ``start`` (2,) [m], grown."""
    disc = shapely.Point(start).buffer(START_DISC / math.cos(math.pi / 32), quad_segs=8)
    return lp.image(disc, IMAGE_ROOM)


def goal_image(lp: LogPolar, goal: shapely.Geometry) -> shapely.Geometry:
    """The image of the goal disc's polygon ``goal`` [m], grown."""
    return lp.image(goal, IMAGE_ROOM)


def both_ways(rules: PushRules, start: np.ndarray, target: np.ndarray, goal: shapely.Geometry, *,
              budget: float = 1.0) -> BothWays:
    """``F`` from the start without ``B`` for at most :data:`FORWARD_FIRST` updates; unless it reached or closed,
    ``B`` closed from the goal (``goal``: a polygon [m] holding the target's goal disc), then ``F`` from the
    start within ``B`` (module docstring), each ``F`` stopping once it comes within :data:`START_DISC` of the
    goal; ``budget`` scales the block updates of ``B`` and of ``F`` within it."""
    lp = LogPolar.about(rules, target)
    world = PolarWorld.of(rules, lp)
    g = goal_image(lp, goal)
    whole = shapely.union(world.space, g)
    first = _ahead(rules, world, g, start, whole, FORWARD_FIRST)  # not scaled: a larger budget skips B no more often
    if BUDGET_SPENT not in first.stopped:  # reached the goal, or closed: B is the whole space
        return _ended(world, g, whole, grid_over(whole, BACK_CELL), first, first.blocks_processed, " (without B)")
    back = backward_set(rules, world.space, g, lp.forward(start)[0], h=BACK_CELL, gap=-1.0,
                        max_blocks=round(BACK_BLOCKS * budget), model=lambda box: world.block_faces(rules, box))
    done = first.blocks_processed + back.blocks_processed
    if back.region is None:
        return BothWays(world, None, None, None, None, f"the set F without B: {first.stopped}; the set B: "
                        f"{back.stopped}", done)
    ahead = _ahead(rules, world, g, start, back.region, round(FORWARD_BLOCKS * budget))
    return _ended(world, g, back.region, back.grid, ahead, done + ahead.blocks_processed, " (within B, after "
                  f"{first.blocks_processed} updates without it)")


def _ahead(rules: PushRules, world: PolarWorld, g: shapely.Geometry, start: np.ndarray, back: shapely.Geometry,
           max_blocks: int) -> BackwardResult:
    """``F``: the forward set from the start's disc, each face held only within ``back`` (``B``), stopping
    within :data:`START_DISC` of the goal image ``g``."""
    shapely.prepare(back)
    inside = shapely.intersection(world.space, back)
    return backward_set(rules, shapely.union(inside, g), start_disc(world.map, start), shapely.centroid(g).coords[0],
                        h=FORWARD_CELL, gap=_goal_gap(g), max_blocks=max_blocks, exact=True,
                        model=lambda box: world.block_faces(rules, box, reverse=True, within=back))


def _ended(world: PolarWorld, g: shapely.Geometry, back: shapely.Geometry, back_grid: BlockGrid,
           ahead: BackwardResult, done: int, note: str) -> BothWays:
    """What :func:`both_ways` found once ``F`` (``ahead``, within ``back``) stopped or closed (``g``: the goal
    image)."""
    if ahead.region is None:
        why = ahead.stopped if BUDGET_SPENT in ahead.stopped else "it came within the gap of the target's goal disc"
        return BothWays(world, back, back_grid, None, None, f"the set F{note}: {why}", done)
    if shapely.distance(ahead.region, g) <= START_DISC:
        return BothWays(world, back, back_grid, None, None, f"the set F{note} came within the gap of the goal", done)
    return BothWays(world, back, back_grid, ahead.region, ahead.grid, "", done)


def _goal_gap(g: shapely.Geometry) -> float:
    """The gap [m] from the goal image's centroid at which ``F`` stops: the goal's farthest point plus
    :data:`START_DISC` (``backward_set`` stops on the distance to a point)."""
    c = np.asarray(shapely.centroid(g).coords[0])
    return float(np.max(np.hypot(*(shapely.get_coordinates(g) - c).T))) + START_DISC


def check_both_ways(rules: PushRules, start: np.ndarray, target: np.ndarray, goal: shapely.Geometry,
                    extra: dict[str, Any]) -> list[str]:
    """What is wrong with the stored sets of a ``forward_backward`` certificate (``extra``: the map, the sets
    as WKT of the (U, V) plane, their grids; empty: it holds), the cones and zones made anew from ``rules``:
    ``B`` holds the goal and is closed backward on every block of its grid, which covers the push space;
    ``F`` holds the start's disc, keeps :data:`START_DISC` from the goal and is closed forward within ``B``."""
    try:
        lp, back, ahead = stored_sets(rules.base, extra)
        grids = [BlockGrid(tuple(d["origin"]), float(d["h"]), tuple(d["shape"]))  # type: ignore[arg-type]
                 for d in (extra["back_grid"], extra["ahead_grid"])]
    except (KeyError, TypeError, ValueError, shapely.errors.GEOSException) as e:
        return [f"the stored sets cannot be read: {e}"]
    if lp != LogPolar.about(rules, target):
        return ["the map is not the one about the Omni's axis and the target"]
    world = PolarWorld.of(rules, lp)
    g, seed = goal_image(lp, goal), start_disc(lp, start)
    problems = []
    if not shapely.covers(shapely.buffer(back, 1e-9), g):
        problems.append("B does not hold the target's goal disc")
    if not shapely.covers(shapely.buffer(ahead, 1e-9), seed):
        problems.append("F does not hold the start's disc")
    if shapely.distance(ahead, g) <= START_DISC:
        problems.append("F comes within the gap of the target's goal disc")
    if not shapely.covers(grids[0].covered(), shapely.union(world.space, g)):
        problems.append("B's grid does not cover the push space")
    if not shapely.covers(grids[1].covered(), shapely.union(shapely.intersection(world.space, back), seed)):
        problems.append("F's grid does not cover the push space within B")
    if problems:
        return problems
    shapely.prepare(back)
    for name, region, grid, model in (
            ("B", back, grids[0], lambda box: world.block_faces(rules, box)),
            ("F", ahead, grids[1], lambda box: world.block_faces(rules, box, reverse=True, within=back))):
        bad = unclosed_block(region, grid, model)
        if bad is not None:
            return [f"{name}: block {bad[0]} is not closed ({bad[1] * 1e6:.3g} mm^2 outside the set)"]
    return []


def stored_sets(base: tuple[float, float], extra: dict[str, Any]
                ) -> tuple[LogPolar, shapely.Geometry, shapely.Geometry]:
    """The map about ``base`` (2,) [m] (the Omni's axis) and the sets ``B`` and ``F`` (of its plane) that a
    ``forward_backward`` certificate stores in ``extra`` (:func:`certificate_data`)."""
    lp = LogPolar((float(base[0]), float(base[1])), float(extra["map"]["r0"]), float(extra["map"]["phi0"]))
    return lp, shapely.from_wkt(extra["back_wkt"]), shapely.from_wkt(extra["ahead_wkt"])


def certificate_data(found: BothWays) -> dict[str, Any]:
    """The stored part of a ``forward_backward`` certificate (:func:`check_both_ways` reads it)."""
    assert found.back is not None and found.ahead is not None and found.back_grid and found.ahead_grid
    return {"map": found.world.map.to_dict(),
            "back_wkt": shapely.to_wkt(found.back, rounding_precision=-1),
            "ahead_wkt": shapely.to_wkt(found.ahead, rounding_precision=-1),
            "back_grid": found.back_grid.to_dict(), "ahead_grid": found.ahead_grid.to_dict(),
            "start_disc": START_DISC}


def world_region(lp: LogPolar, g: shapely.Geometry) -> shapely.Geometry:
    """The world image [m] of polygons ``g`` of the (U, V) plane (edges cut first; for drawing)."""
    return _mapped(g, lp.inverse)


def _mapped(g: shapely.Geometry, point_map: Any) -> shapely.Geometry:
    """The polygons ``g`` with every vertex moved by ``point_map`` ((K, 2) -> (K, 2)), edges cut to
    :data:`DENSE` first (of ``g``'s plane), made valid."""
    g = polygonal(g)
    if g.is_empty:
        return g
    parts = []
    for p in shapely.get_parts(shapely.segmentize(g, DENSE)):
        holes = [point_map(shapely.get_coordinates(h)) for h in p.interiors]
        parts.append(shapely.make_valid(shapely.Polygon(point_map(shapely.get_coordinates(p.exterior)), holes)))
    return polygonal(shapely.union_all(parts))
