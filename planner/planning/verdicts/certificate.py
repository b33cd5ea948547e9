"""Certificates that no plan exists under :class:`~tooltransfer.planner.planning.verdicts.rules.PushRules`, and
their independent check.

Kinds, cheapest first:

- ``start_unpushable``: no face can hold the puck at the start (it is outside every face's region,
  or inside an obstacle's zone), so the puck never moves, and the start is not at the target;
- ``target_unpushable``: no face can hold the puck anywhere within ``goal_tol`` of the target, so no
  push ends there;
- ``polar_invariant``: a quantity every admissible push increases (the puck's polar angle about the
  Omni's axis less a function of its distance from it, :mod:`.spiral`) is lower everywhere on the
  target's goal disc than at the start;
- ``backward_reachable``: a closed set holding the target's goal disc (:mod:`.backward`) leaves the
  start out by at least ``gap``;
- ``switch_separated``: closed sets of the positions each face may push the puck to from the start, a
  face's set passed to another only where the tool can get from one's contact to the other's round the
  resting puck (:mod:`.switch_forward`, :mod:`.switch_space`), leave the target out by at least ``gap``
  (:func:`certify_switches`: tried after the search);
- ``forward_backward``: on blocks of log-polar cells about the Omni's axis (where a face's cone does not
  turn with the polar angle), a closed set of the positions from which the target may be reachable, and
  within it a closed set of the positions reachable from the start, which leaves the target out
  (:mod:`.polar_sets`, :func:`certify_both_ways`: tried last).

A certificate stores its kind, the rules' parameters, the sets as polygons and the grid; anyone can
replay it with :func:`check_certificate`, which recomputes the cones from the rules and checks the
closure block by block on the stored set.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely

from tooltransfer.planner.planning.verdicts.backward import (
    BlockGrid,
    backward_set,
    block_face,
    block_faces,
    face_regions,
    grid_over,
    unclosed_block,
)
from tooltransfer.planner.planning.verdicts.bounds import obstacle_zone, push_space
from tooltransfer.planner.planning.verdicts.polar_sets import (
    START_DISC,
    both_ways,
    certificate_data,
    check_both_ways,
    world_region,
)
from tooltransfer.planner.planning.verdicts.rules import PushRules
from tooltransfer.planner.planning.verdicts.spiral import V_GAP, Spiral, check_spiral, invariant, start_side
from tooltransfer.planner.planning.verdicts.switch_forward import check_forward, forward_sets
from tooltransfer.planner.planning.verdicts.switch_space import PlacementSpace

#: The start's least distance [m] from a certificate's set (far above the polygons' rounding).
START_GAP = 5e-4
#: The least start gap [m] a stored certificate may claim (far above the rounding).
MIN_START_GAP = 1e-5


@dataclass(frozen=True)
class ExactBackward:
    """The last attempt at a ``backward_reachable`` certificate: cells of ``cell`` [m], a start gap of ``gap``
    [m], pieces stored exactly (:func:`~.backward.backward_set`), at most ``blocks`` block updates and
    ``vertices`` vertices grown (each times the budget)."""

    cell: float
    gap: float
    blocks: int
    vertices: int


#: Tried by ``decide.attach_verdict`` once the search has failed: it certifies ``exec60-00015``, where the
#: growth of the stored pieces alone takes the default sets to the start, after 344,672 vertices grown
#: (9,529 updates, some 20 s). The vertex bound stops it where exact pieces gather vertices: on
#: ``tiny-00001`` of ``examples/tiny_batch.yaml`` at its seed 11 one block's pieces reached 26,755 and the set
#: ran for minutes unbounded (benchmarks/README.md, twenty-first and twenty-second sessions).
LAST_BACKWARD = ExactBackward(0.0025, 5e-5, 12000, 600_000)


@dataclass
class Certificate:
    """A proof that the start cannot reach the target under the rules.

    Attributes:
        kind: ``"start_unpushable"``, ``"target_unpushable"`` or ``"backward_reachable"``.
        reason: one sentence for people.
        start, target: shape (2,) [m].
        rules: the parameters the proof is relative to (:meth:`PushRules.to_dict`).
        region: the backward-reachable set's polygons [m] (``backward_reachable``), else None.
        space: the push space's polygons [m] (where any face can hold the puck).
        grid: ``{"origin", "h", "shape"}`` of the blocks (``backward_reachable``).
        time: seconds spent.
    """

    kind: str
    reason: str
    start: tuple[float, float]
    target: tuple[float, float]
    rules: dict[str, Any]
    space: shapely.Geometry
    region: shapely.Geometry | None = None
    grid: BlockGrid | None = None
    time: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON data (polygons as WKT, lengths in m)."""
        return {
            "kind": self.kind, "reason": self.reason, "start": list(self.start), "target": list(self.target),
            "rules": self.rules, "space_wkt": shapely.to_wkt(self.space, rounding_precision=-1),
            "region_wkt": None if self.region is None else shapely.to_wkt(self.region, rounding_precision=-1),
            "grid": None if self.grid is None else self.grid.to_dict(),
            "start_gap": START_GAP, "time": self.time, **self.extra,
        }


def _goal(rules: PushRules, target: np.ndarray) -> shapely.Geometry:
    """A polygon holding the disc of radius ``goal_tol`` about the target (circumscribed)."""
    n = 32
    r = rules.goal_tol / np.cos(np.pi / n)
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return shapely.Polygon(np.column_stack([r * np.cos(a), r * np.sin(a)]) + target)


#: Cell sides [m] of the backward-reachable set, tried in turn while the set reaches the start: a finer
#: grid cuts fewer corners round the obstacles and turns each face's cone by less over a block (a push
#: piece is shorter than half a cell), at about four times the blocks.
CELL_SIDES = (0.01, 0.005, 0.0025)
#: Block updates a finer grid may make (it starts again from the goal; the first grid has the rest of
#: ``max_blocks``), one per grid after the first. The finest grid's share is small: at about 4 ms per
#: block it costs at most some 6 s where the set still reaches the start (benchmarks/README.md).
FINE_BLOCKS = (5000, 1500)


def certify(rules: PushRules, start: np.ndarray, target: np.ndarray, *, h: tuple[float, ...] = CELL_SIDES,
            max_blocks: int = 20000, fine_blocks: tuple[int, ...] = FINE_BLOCKS, gap: float = START_GAP,
            exact: bool = False, max_vertices: int | None = None) -> tuple[Certificate | None, str]:
    """A certificate that ``start`` (2,) [m] cannot reach ``target`` (2,) [m] under ``rules``, or None
    with what was tried (an honest "not proved": the task may still be infeasible). The
    backward-reachable set is built on cells of side ``h[0]`` [m], then of each next side in turn while it
    comes within ``gap`` [m] of the start (pieces stored ``exact``: :func:`~.backward.backward_set`);
    ``max_blocks`` block updates in all, at most ``fine_blocks[k]`` on the grid ``h[k + 1]`` (the last
    allowance for any further grid); ``max_vertices``: the vertices grown each set may take (None: no bound)."""
    t0 = time.perf_counter()
    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    if np.hypot(*(start - target)) <= rules.goal_tol:
        return None, "the start is at the target"
    space = push_space(rules)
    goal = _goal(rules, target)
    common = {"start": (float(start[0]), float(start[1])), "target": (float(target[0]), float(target[1])),
              "rules": rules.to_dict(), "space": space}
    if shapely.distance(space, shapely.Point(start)) > START_GAP:
        return Certificate("start_unpushable", "no face of the tool can hold the puck at the start (out of every "
                           "face's reach, or inside an obstacle's margin), so it never moves", **common,
                           time=time.perf_counter() - t0), ""
    if shapely.distance(space, goal) > START_GAP:
        return Certificate("target_unpushable", "no face of the tool can hold the puck within "
                           f"{rules.goal_tol * 1e3:.2g} mm of the target, so no push ends there", **common,
                           time=time.perf_counter() - t0), ""
    sp = invariant(rules, start, target)
    if sp is not None and check_spiral(rules, sp, start, target, separating=False):
        sp = None  # (refused by its own check: never seen)
    if sp is not None and sp.v_goal < sp.v_start - V_GAP:
        return Certificate("polar_invariant", "every admissible push increases the puck's polar angle about the "
                           f"Omni's axis {'less' if sp.sigma > 0 else 'negated, less'} a function of its distance "
                           "from the axis (checked on 1 mm bands of distance, every face's cone at every offset), "
                           f"and that quantity is {(sp.v_start - sp.v_goal) * 1e3:.1f} mrad lower everywhere within "
                           f"{rules.goal_tol * 1e3:.2g} mm of the target than at the start", **common,
                           region=shapely.intersection(space, start_side(rules, sp, start)),
                           time=time.perf_counter() - t0, extra={"invariant": sp.to_dict()}), ""
    # a quantity no push decreases that does not separate start and target still bounds where a plan goes
    zone = None if sp is None else restricted_zone(rules, sp, start, space, goal)
    inside = space if zone is None else shapely.difference(space, zone)
    tried, left = [], max_blocks
    finer = "" if gap == START_GAP and not exact else f", a start gap of {gap * 1e3:g} mm{', pieces exact' * exact}"
    for k, side in enumerate(h):
        allowed = left if k == 0 else min(left, fine_blocks[min(k, len(fine_blocks)) - 1])
        back = backward_set(rules, inside, goal, start, h=side, gap=gap, max_blocks=allowed, zone=zone, exact=exact,
                            max_vertices=max_vertices)
        tried.append(f"cells of {side * 1e3:g} mm{finer}: {back.stopped} (after {back.blocks_processed} blocks)")
        left -= back.blocks_processed
        if back.region is not None or left <= 0:
            break
    if back.region is None:
        return None, "backward-reachable set of the target: " + "; ".join(tried)
    within = "" if sp is None else ("on the side of the start of a quantity no push decreases (the polar angle "
                                    "about the Omni's axis less a function of the distance) ")
    cert = Certificate("backward_reachable", "the positions from which any push sequence could reach the target "
                       f"{within}(over-approximated: every face's cone at every heading its reach allows, the tool "
                       "body only where it overlaps an obstacle whatever the contact, switches free) leave the start "
                       f"out by {shapely.distance(back.region, shapely.Point(start)) * 1e3:.1f} mm", **common,
                       region=back.region, grid=back.grid, time=time.perf_counter() - t0,
                       extra={"blocks_processed": back.blocks_processed, "start_gap": gap}
                       | ({} if sp is None else {"invariant": sp.to_dict()}))
    return _issued(cert, rules, t0, "backward-reachable set of the target: its check failed: ")


def certify_exact_backward(rules: PushRules, start: np.ndarray, target: np.ndarray, *, budget: float = 1.0,
                           last: ExactBackward = LAST_BACKWARD) -> tuple[Certificate | None, str]:
    """:func:`certify` with the set of exact pieces ``last`` (its block updates and vertices times ``budget``):
    the verdict's last backward attempt (``decide.attach_verdict``, once the search has failed)."""
    return certify(rules, start, target, h=(last.cell,), max_blocks=round(last.blocks * budget), gap=last.gap,
                   exact=True, max_vertices=round(last.vertices * budget))


def restricted_zone(rules: PushRules, sp: Spiral, start: np.ndarray, space: shapely.Geometry,
                    goal: shapely.Geometry) -> shapely.Geometry:
    """Where no plan from ``start`` goes: the obstacles' zone and, about the push ``space`` and the
    ``goal``, the far side of the quantity ``sp`` no push decreases (:func:`.spiral.start_side`)."""
    around = shapely.buffer(shapely.envelope(shapely.union(space, goal)), 0.05, join_style="mitre")
    return shapely.union(obstacle_zone(rules), shapely.difference(around, start_side(rules, sp, start)))


def check_certificate(cert: Certificate, rules: PushRules, placements: PlacementSpace | None = None) -> list[str]:
    """What is wrong with ``cert`` under ``rules`` (empty: it holds): the rules it was made for, the
    start's and the goal's place, and for ``backward_reachable`` the closure of its set on every block,
    with the cones recomputed from ``rules``; for ``switch_separated`` the closure of each face's set with
    the tool's ``placements`` (of the same tool, Omni and obstacles) made anew."""
    problems: list[str] = []
    if cert.rules != rules.to_dict():
        problems.append("the certificate was made for other rules")
    start, target = np.asarray(cert.start), np.asarray(cert.target)
    space = push_space(rules)
    goal = _goal(rules, target)
    if np.hypot(*(start - target)) <= rules.goal_tol:
        problems.append("the start is at the target")
    if cert.kind == "start_unpushable":
        if shapely.distance(space, shapely.Point(start)) <= START_GAP:
            problems.append("a face can hold the puck at the start")
    elif cert.kind == "target_unpushable":
        if shapely.distance(space, goal) <= START_GAP:
            problems.append("a face can hold the puck at the target")
    elif cert.kind == "polar_invariant":
        inv = cert.extra.get("invariant")
        if not isinstance(inv, dict):
            return [*problems, "no invariant stored"]
        problems += check_spiral(rules, Spiral.from_dict(inv), start, target)
    elif cert.kind == "backward_reachable":
        region, grid = cert.region, cert.grid
        if region is None or grid is None:
            return [*problems, "no set or grid stored"]
        if not shapely.covers(shapely.buffer(region, 1e-9), goal):
            problems.append("the set does not hold the target's goal disc")
        gap = _stored_gap(cert)
        if isinstance(gap, str):
            return [*problems, gap]
        if shapely.distance(region, shapely.Point(start)) <= gap:
            problems.append("the set does not leave the start out")
        zone, regions = obstacle_zone(rules), face_regions(rules)
        if "invariant" in cert.extra:  # the set was grown on the start's side of a quantity no push decreases
            sp = Spiral.from_dict(cert.extra["invariant"])
            problems += check_spiral(rules, sp, start, target, separating=False)
            zone = restricted_zone(rules, sp, start, space, goal)
            space = shapely.difference(space, zone)
        if not shapely.covers(grid.covered(), shapely.union(space, goal)):
            problems.append("the grid does not cover the push space")
        bad = unclosed_block(region, grid, lambda box: block_faces(rules, box, zone, regions))
        if bad is not None:
            problems.append(f"block {bad[0]} is not closed ({bad[1] * 1e6:.3g} mm^2 outside the set)")
    elif cert.kind == "switch_separated":
        problems += _check_switches(cert, rules, placements, start, goal)
    elif cert.kind == "forward_backward":
        problems += check_both_ways(rules, start, target, goal, cert.extra)
    else:
        problems.append(f"unknown kind {cert.kind!r}")
    return problems


#: Cell side [m] of the ``switch_separated`` sets (a block's puck may be anywhere in it: the finest grid
#: of :data:`CELL_SIDES`).
SWITCH_CELL = 0.0025
#: Block updates the ``switch_separated`` sets may make (benchmarks/README.md: 1357 where they closed on the
#: verdict benchmark, some 10 s of CPU).
SWITCH_BLOCKS = 3000


@dataclass(frozen=True)
class SwitchGrid:
    """One attempt at the ``switch_separated`` sets: cells of ``cell`` [m], a start disc of radius ``gap``
    [m] (also the least distance kept from the goal), pieces stored ``exact`` or grown (:func:`~.switch_forward.
    forward_sets`), at most ``blocks`` block updates (times the budget)."""

    cell: float
    gap: float
    exact: bool
    blocks: int


#: The attempts, in turn while the sets reach the target. The second is for tasks at the edge of the
#: rules, where a push's lowest edge passes an obstacle's margin by a fraction of a millimetre: the first's
#: start disc and the heading's spread over its blocks take the sets under it, the growth of its stored
#: pieces along the margin (benchmarks/README.md, twentieth and twenty-first sessions).
SWITCH_GRIDS = (SwitchGrid(SWITCH_CELL, START_GAP, False, SWITCH_BLOCKS),
                SwitchGrid(0.5 * SWITCH_CELL, 0.1 * START_GAP, True, 4000))


def start_faces(rules: PushRules, start: np.ndarray) -> list[str]:
    """The faces that may hold the puck at ``start`` (2,) [m]: their hold set in a box of 2 um about it
    (:func:`~.backward.block_face`, an over-approximation) comes within 0.1 um of it."""
    box = (start[0] - 1e-6, start[1] - 1e-6, start[0] + 1e-6, start[1] + 1e-6)
    zone, point = obstacle_zone(rules), shapely.Point(start)
    out = []
    for rule, region in zip(rules.faces, face_regions(rules), strict=True):
        m = block_face(rules, rule, region, box, zone)
        if m is not None and shapely.distance(m[1], point) <= 1e-7:
            out.append(rule.name)
    return out


def certify_switches(rules: PushRules, space: PlacementSpace, start: np.ndarray, target: np.ndarray, *,
                     budget: float = 1.0, grids: tuple[SwitchGrid, ...] = SWITCH_GRIDS
                     ) -> tuple[Certificate | None, str]:
    """A ``switch_separated`` certificate (module docstring) that ``start`` (2,) [m] cannot reach ``target``
    (2,) [m] under ``rules`` with switches only where the tool's placements ``space`` join the faces'
    contacts, or None with what was tried; each of ``grids`` in turn, ``budget`` scaling its block updates."""
    t0 = time.perf_counter()
    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    pushes, goal, zone = push_space(rules), _goal(rules, target), obstacle_zone(rules)
    holders = start_faces(rules, start)
    tried = []
    for attempt in grids:
        grid = grid_over(shapely.union_all([pushes, goal, shapely.Point(start).buffer(attempt.gap)]), attempt.cell)
        res = forward_sets(rules, space, grid, start, goal, holders, gap=attempt.gap,
                           max_blocks=round(attempt.blocks * budget), zone=zone, exact=attempt.exact)
        exact = ", pieces exact" if attempt.exact else ""
        tried.append(f"cells of {attempt.cell * 1e3:g} mm, a start disc of {attempt.gap * 1e3:g} mm{exact}: "
                     f"{res.stopped} (after {res.blocks_processed} blocks)")
        if res.regions is None:
            continue
        union = shapely.union_all(list(res.regions.values()))
        cert = Certificate("switch_separated", "the positions each face could push the puck to from the start "
                           "(over-approximated as for the backward-reachable set), a face's passed to another only "
                           "where the tool can get from the one's contact to the other's round the resting puck "
                           "within the Omni's joints, leave the target out by "
                           f"{shapely.distance(union, goal) * 1e3:.2f} mm",
                           start=(float(start[0]), float(start[1])), target=(float(target[0]), float(target[1])),
                           rules=rules.to_dict(), space=pushes, region=union, grid=grid,
                           extra={"holders": holders, "blocks_processed": res.blocks_processed,
                                  "start_gap": attempt.gap, "placements": _placements_of(space),
                                  "regions_wkt": {f: shapely.to_wkt(g, rounding_precision=-1)
                                                  for f, g in res.regions.items()}})
        issued, why = _issued(cert, rules, t0, "; their check failed: ", placements=space)
        if issued is not None:
            return issued, ""
        tried[-1] += why
    return None, ("the faces' sets from the start with switches only where the tool gets round the puck ("
                  + "; ".join(tried) + ")")


def _check_switches(cert: Certificate, rules: PushRules, space: PlacementSpace | None, start: np.ndarray,
                    goal: shapely.Geometry) -> list[str]:
    """The ``switch_separated`` part of :func:`check_certificate`."""
    if space is None:
        return ["the tool's placement space is needed to check a switch_separated certificate"]
    regions, grid = cert.extra.get("regions_wkt"), cert.grid
    if not isinstance(regions, dict) or grid is None:
        return ["no sets or grid stored"]
    if cert.extra.get("placements") != _placements_of(space):
        return ["the certificate was made for another tool or Omni (its placements differ)"]
    holders = start_faces(rules, start)
    if sorted(holders) != sorted(cert.extra.get("holders", [])):
        return ["the faces that may hold the puck at the start differ"]
    gap = _stored_gap(cert)
    if isinstance(gap, str):
        return [gap]
    return check_forward(rules, space, grid, {f: shapely.from_wkt(w) for f, w in regions.items()},
                         start, goal, holders, gap, obstacle_zone(rules))


def _stored_gap(cert: Certificate) -> float | str:
    """The start gap [m] ``cert`` claims (:data:`START_GAP` where it stores none), or what is wrong with it:
    a gap below :data:`MIN_START_GAP` (the rounding) proves nothing."""
    gap = cert.extra.get("start_gap", START_GAP)
    if not (isinstance(gap, float) and gap >= MIN_START_GAP):
        return f"the start gap {gap!r} is not a length of at least {MIN_START_GAP} m"
    return gap


def _placements_of(space: PlacementSpace) -> dict[str, Any]:
    """What a ``switch_separated`` certificate's placements are made of, beyond its rules: the tool's
    outline [m, tool frame], the Omni's axis [m], waist [rad] and reach [m] ranges (JSON data)."""
    return {"outline": np.asarray(space.tool.outline.exterior.coords).tolist(), "base": space.base.tolist(),
            "base_yaw": space.base_yaw, "q1_range": list(space.q1_range), "u_range": list(space.u_range)}


def certify_both_ways(rules: PushRules, start: np.ndarray, target: np.ndarray, *, budget: float = 1.0
                      ) -> tuple[Certificate | None, str]:
    """A ``forward_backward`` certificate (module docstring, :mod:`.polar_sets`) that ``start`` (2,) [m] cannot
    reach ``target`` (2,) [m] under ``rules``, or None with what was tried; ``budget`` scales the block updates."""
    t0 = time.perf_counter()
    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    goal = _goal(rules, target)
    found = both_ways(rules, start, target, goal, budget=budget)
    tried = f"the sets both ways on log-polar cells: {found.stopped or 'closed'} (after {found.blocks} blocks)"
    if found.ahead is None:
        return None, tried
    lp = found.world.map
    cert = Certificate("forward_backward", "on cells of log-polar coordinates about the Omni's axis (where a "
                       "face's cone turns with the distance only), the positions from which the target could be "
                       "reached, and within them the positions a plan from the start could reach (over-approximated "
                       "as for the backward-reachable set), leave the target out by "
                       f"{shapely.distance(found.ahead, lp.image(goal, 0.0)) * 1e3:.1f} mm (of that plane)",
                       start=(float(start[0]), float(start[1])), target=(float(target[0]), float(target[1])),
                       rules=rules.to_dict(), space=push_space(rules), region=world_region(lp, found.ahead),
                       extra={"blocks_processed": found.blocks, "start_gap": START_DISC, **certificate_data(found)})
    return _issued(cert, rules, t0, f"{tried}; its check failed: ")


def _issued(cert: Certificate, rules: PushRules, t0: float, failed: str, placements: PlacementSpace | None = None
            ) -> tuple[Certificate | None, str]:
    """``(cert, "")`` with its time (the seconds since ``t0``, its check included) where
    :func:`check_certificate` finds nothing wrong with it, else ``(None, failed + the problems)``."""
    problems = check_certificate(cert, rules, placements=placements)
    if problems:
        return None, failed + "; ".join(problems)
    cert.time = time.perf_counter() - t0
    return cert, ""
