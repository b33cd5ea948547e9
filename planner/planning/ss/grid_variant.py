"""The ``grid`` switch planner: a search over every placement the Omni can give the tool, then an exact check.

The ``opt`` NLP is local and the ``arch`` reference backs off along the face's normal and arches round the
object; both give up on switches that exist, e.g. near the Omni's inner reach, where backing off leaves it.
On the Omni the tool's placement in the table plane has two degrees of freedom, the waist angle ``q1`` and
the arm-plane reach ``u`` (:mod:`tooltransfer.planner.planning.verdicts.switch_space`; the joints allow the
box ``q1_range x u_range``). So a switch is a path in that box, and a grid over it is searched whole:

1. the grid's neighbours along an axis are at most ``step <= move`` [m] apart at any tool point
   (``dq <= move / r_max``, ``du <= move``); a point is *free* where the tool's outline, placed there, keeps
   ``clearance + step`` from the object and ``TOOL_MARGIN + step`` from the obstacles (shapely, on polygons
   that hold the round shapes), so that a move between two free neighbours, each point of which is within
   ``step`` of one of its ends, keeps ``clearance`` and ``TOOL_MARGIN``. The two contact poses touch the
   object, so they are not free: each leaves (and the other is reached) by a straight move in ``(q1, u)`` to
   a free point nearby, swept exactly (:func:`~tooltransfer.planner.planning.ss.verify.sweep_checks`);
2. the shortest way through the free points (8 neighbours, lengths in metres of tool motion) joins the two
   sets of verified leaving moves (scipy's Dijkstra). ``clearance`` is the task's ``ss.clearance`` (the
   ``opt`` NLP's margin), kept whole: a way nearer the object is made exactly as planned but does not survive
   the object's drift in an open-loop run (a way 0.5 mm from it, tried, knocked the object of
   ``verd200-00143`` 12 mm off its target in MuJoCo);
3. the way is shortened where a straight move in ``(q1, u)`` between two of its points keeps free, and
   sampled at most :data:`SAMPLE` [m] apart in the box (a straight move in ``(q1, u)`` stays in the box: the
   whole path keeps within the Omni's joints, and the assembly's interpolation between samples deviates
   from the arc by under a micrometre);
4. the whole path is measured exactly like every switch path: the swept outline against the object
   (penetration at most :data:`TOUCH_TOL`, the contacts touch; ``clearance`` between the two leaving moves)
   and the obstacles (at least ``TOOL_MARGIN``), and the reach at every sample
   (:func:`~tooltransfer.tools.omni.ik.joint_path`); its ends are the contact poses themselves (a pose whose
   heading is not the Omni's is refused). A path that fails is never returned: the result is ``infeasible``
   with what failed.

The search is complete on its grids between the leaving moves, which are straight and at most
:data:`LEAVE_REACH` long: where it finds nothing, finer grids or other leaving moves may, and the reason says so
(the planner refuses the switch; it proves nothing: certificates use
:mod:`tooltransfer.planner.planning.verdicts.switch_space`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import shapely
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from tooltransfer.planner.planning.assemble import SwitchPlanner
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.ss.result import SwitchPath
from tooltransfer.planner.planning.ss.verify import SweepCheck, pose_depth_and_gap, sweep_checks
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.omni.reach import ReachSector, reach_sector
from tooltransfer.tools.pose import Pose2D, rotation

#: Grids tried in turn: the most [m] any tool point moves between neighbouring points.
MOVES = (1e-3, 5e-4)
#: Segments per quarter circle of the buffers that make the blocked placements (grown to hold the round shapes).
QUAD_SEGS = 32
#: Largest distance [m] any tool point moves between two samples of the returned path.
SAMPLE = 2.5e-4
#: How far [m] (in tool motion) from a contact pose its leaving moves may end.
LEAVE_REACH = 0.02
#: Leaving moves tried per contact pose (the nearest free points first, spread over directions).
LEAVE_TRIES = 48
#: Penetration depth [m] accepted as touching at the two contacts (as the ``opt`` variant's ``touch_tol``).
TOUCH_TOL = 5e-6
#: Margin [m] kept from the edges of the joints' box (the interpolation between samples stays inside).
BOX_MARGIN = 2e-5


class _Grid:
    """The placement box of ``sector`` on a grid ``move`` [m] apart at any point of a tool of ``reach`` [m]."""

    def __init__(self, sector: ReachSector, reach: float, move: float) -> None:
        self.sec = sector
        self.r_max = math.hypot(sector.u_range[1] + reach, abs(D_TOOL) + reach)
        lo_q, hi_q = sector.q1_range[0] + BOX_MARGIN / self.r_max, sector.q1_range[1] - BOX_MARGIN / self.r_max
        lo_u, hi_u = sector.u_range[0] + BOX_MARGIN, sector.u_range[1] - BOX_MARGIN
        self.qs = np.linspace(lo_q, hi_q, max(2, math.ceil((hi_q - lo_q) * self.r_max / move) + 1))
        self.us = np.linspace(lo_u, hi_u, max(2, math.ceil((hi_u - lo_u) / move) + 1))

    def scaled(self, qu: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(q1, u)`` (..., 2) in metres of tool motion: ``(r_max q1, u)`` (a bound on any point's move)."""
        return np.asarray(qu) * np.array([self.r_max, 1.0])

    def poses(self, qu: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Tool origins (K, 2) [m] and headings (K,) [rad] at the placements ``qu`` (K, 2)."""
        qu = np.asarray(qu, dtype=np.float64).reshape(-1, 2)
        return self.sec.point(qu[:, 0], qu[:, 1]), self.sec.base_yaw + qu[:, 0] - math.pi / 2


def placement_of(sector: ReachSector, pose: NDArray[np.float64]) -> NDArray[np.float64]:
    """The waist angle ``q1`` [rad] and reach ``u`` [m], (2,), of the tool pose ``(x [m], y [m], yaw [rad])``
    whose heading is the Omni's (``yaw = base_yaw + q1 - pi/2``)."""
    a = float(pose[2]) + math.pi / 2
    q1 = math.remainder(a - sector.base_yaw, 2 * math.pi)
    u = (pose[0] - sector.centre[0]) * math.cos(a) + (pose[1] - sector.centre[1]) * math.sin(a)
    return np.array([q1, u])


def _outlines(ring: NDArray[np.float64], xy: NDArray[np.float64], yaw: float) -> NDArray:
    """The outline ``ring`` (V, 2) [tool frame, m] placed at origins ``xy`` (K, 2) [m], all at the heading
    ``yaw`` [rad] (a row of the grid: one waist angle): (K,) shapely polygons."""
    return shapely.polygons((ring @ rotation(yaw).T)[None, :, :] + xy[:, None, :])


def _blocked(setting: Setting, grid: _Grid, obj: NDArray[np.float64], clearance: float) -> NDArray[np.bool_]:
    """Grid points (Q, U) where the outline comes within ``clearance`` of the object or ``TOOL_MARGIN`` of an
    obstacle, each plus the grid's step: between two neighbouring points no tool point moves more than twice
    the step, so a move between free points keeps both."""
    ring = np.asarray(setting.tool.outline.exterior.coords)
    step = float(np.max(np.diff(grid.scaled(np.column_stack([grid.qs[:2], grid.us[:2]])), axis=0)))
    grow = 1.0 / math.cos(math.pi / (4 * QUAD_SEGS))  # the buffers' polygons hold the true round shapes
    puck = shapely.Point(obj).buffer(grow * (setting.radius + clearance + step), quad_segs=QUAD_SEGS)
    walls = [shapely.Point(o.centre).buffer(grow * (o.radius + TOOL_MARGIN + step), quad_segs=QUAD_SEGS)
             if isinstance(o, Disc) else o.buffer(grow * (TOOL_MARGIN + step), quad_segs=QUAD_SEGS)
             for o in setting.obstacles]
    shapes = shapely.union_all([puck, *walls])
    shapely.prepare(shapes)
    out = np.zeros((grid.qs.size, grid.us.size), dtype=bool)
    for i, q in enumerate(grid.qs):
        xy, yaw = grid.poses(np.column_stack([np.full(grid.us.size, q), grid.us]))
        out[i] = shapely.intersects(shapes, _outlines(ring, xy, float(yaw[0])))
    return out


def _dense(grid: _Grid, qu: NDArray[np.float64]) -> NDArray[np.float64]:
    """The ``(q1, u)`` polyline ``qu`` (K, 2) sampled so that no tool point moves more than :data:`SAMPLE`."""
    out = [qu[:1]]
    for a, b in itertools.pairwise(qu):
        n = max(1, math.ceil(float(np.sum(np.abs(grid.scaled(b - a)))) / SAMPLE))  # a bound on any point's move
        out.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    return np.vstack(out)


def _swept(setting: Setting, grid: _Grid, obj: NDArray[np.float64], qu: NDArray[np.float64]
           ) -> tuple[NDArray[np.float64], SweepCheck, float, float]:
    """The move through the placements ``qu`` (K, 2), sampled (:func:`_dense`), swept and measured exactly
    (:func:`~tooltransfer.planner.planning.ss.verify.sweep_checks`): its tool origins (M, 2) [m], its check
    against the object (per step), the largest penetration into an obstacle and the least clearance from the
    obstacles [m]."""
    xy, yaw = grid.poses(_dense(grid, qu))
    obj_check, obs = sweep_checks(setting.tool, xy, yaw, Disc(np.asarray(obj, dtype=np.float64), setting.radius),
                                  setting.obstacles)
    return (xy, obj_check, max((o.max_penetration for o in obs), default=0.0),
            min((o.min_clearance() for o in obs), default=math.inf))


def _leaving(setting: Setting, grid: _Grid, obj: NDArray[np.float64], contact: NDArray[np.float64],
             free: NDArray[np.bool_]) -> dict[int, float]:
    """Free grid points (flat index -> length of the move [m]) that a straight move in ``(q1, u)`` from the
    ``contact`` placement (2,) reaches touching the object no deeper than :data:`TOUCH_TOL` and keeping
    ``TOOL_MARGIN`` from the obstacles: the nearest first, at most :data:`LEAVE_TRIES` tried, spread over
    directions (one per 7.5 degrees)."""
    qq, uu = np.meshgrid(grid.qs, grid.us, indexing="ij")
    rel = grid.scaled(np.stack([qq - contact[0], uu - contact[1]], axis=-1))
    dist = np.hypot(rel[..., 0], rel[..., 1])
    near = np.flatnonzero(free.ravel() & (dist.ravel() <= LEAVE_REACH))
    near = near[np.argsort(dist.ravel()[near], kind="stable")]
    sectors = np.floor(np.arctan2(rel[..., 1].ravel()[near], rel[..., 0].ravel()[near]) / math.radians(7.5))
    _, first = np.unique(sectors, return_index=True)
    out: dict[int, float] = {}
    for k in near[np.sort(first)][:LEAVE_TRIES]:
        end = np.array([qq.ravel()[k], uu.ravel()[k]])
        _, obj_check, _, gap_obs = _swept(setting, grid, obj, np.vstack([contact, end]))
        if obj_check.max_penetration <= TOUCH_TOL and gap_obs >= TOOL_MARGIN:  # (a margin kept: no penetration)
            out[int(k)] = float(dist.ravel()[k])
    return out


def _shortest(grid: _Grid, free: NDArray[np.bool_], starts: dict[int, float], goals: dict[int, float]
              ) -> list[int] | None:
    """The shortest way (flat grid indices) through the ``free`` points (8 neighbours) from one of
    ``starts`` to one of ``goals`` (each with the length of its leaving move), or None."""
    n_q, n_u = free.shape
    idx = np.arange(free.size).reshape(free.shape)
    rows, cols, w = [], [], []
    for dq, du in ((0, 1), (1, 0), (1, 1), (1, -1)):
        a = idx[max(0, -dq):n_q - max(0, dq), max(0, -du):n_u - max(0, du)]
        b = idx[max(0, dq):n_q + min(0, dq) or None, max(0, du):n_u + min(0, du) or None]
        both = free.ravel()[a.ravel()] & free.ravel()[b.ravel()]
        step = float(np.hypot(*grid.scaled(np.array([dq * (grid.qs[1] - grid.qs[0]), du * (grid.us[1] - grid.us[0])]))))
        rows += [a.ravel()[both], b.ravel()[both]]
        cols += [b.ravel()[both], a.ravel()[both]]
        w.append(np.full(2 * int(both.sum()), step))
    src, dst = free.size, free.size + 1
    s_k, s_w = np.array(list(starts), dtype=np.int64), np.array(list(starts.values()))
    g_k, g_w = np.array(list(goals), dtype=np.int64), np.array(list(goals.values()))
    r = np.concatenate([*rows, np.full(s_k.size, src), g_k])
    c = np.concatenate([*cols, s_k, np.full(g_k.size, dst)])
    graph = coo_matrix((np.concatenate([*w, s_w + 1e-12, g_w + 1e-12]), (r, c)), shape=(free.size + 2,) * 2).tocsr()
    dist, pred = dijkstra(graph, indices=src, return_predecessors=True)
    if not np.isfinite(dist[dst]):
        return None
    way, k = [], int(pred[dst])
    while k != src:
        way.append(k)
        k = int(pred[k])
    return way[::-1]


def _shortened(grid: _Grid, blocked_at: NDArray[np.bool_], qu: NDArray[np.float64]) -> NDArray[np.float64]:
    """The way ``qu`` (K, 2) with corners cut where every grid point next to the straight move between two
    of its points is free (``blocked_at`` (Q, U) the blocked points)."""

    def clear(a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
        pts = _dense(grid, np.vstack([a, b]))
        i = np.clip(np.searchsorted(grid.qs, pts[:, 0]), 1, grid.qs.size - 1)
        j = np.clip(np.searchsorted(grid.us, pts[:, 1]), 1, grid.us.size - 1)
        return not (blocked_at[i, j] | blocked_at[i - 1, j] | blocked_at[i, j - 1] | blocked_at[i - 1, j - 1]).any()

    out, i = [qu[0]], 0
    while i < len(qu) - 1:
        j = len(qu) - 1
        while j > i + 1 and not clear(qu[i], qu[j]):
            j = max(i + 1, i + (j - i) // 2) if j - i > 8 else j - 1
        out.append(qu[j])
        i = j
    return np.vstack(out)


def _way(grid: _Grid, ends: list[NDArray[np.float64]], leave: list[dict[int, float]], blocked: NDArray[np.bool_]
         ) -> NDArray[np.float64] | None:
    """The placements (K, 2) of the shortest way from ``ends[0]`` to ``ends[1]`` through the points not
    ``blocked``, corners cut, or None where there is none."""
    free = ~blocked
    starts = {k: d for k, d in leave[0].items() if free.ravel()[k]}
    goals = {k: d for k, d in leave[1].items() if free.ravel()[k]}
    way = _shortest(grid, free, starts, goals) if starts and goals else None
    if way is None:
        return None
    at = np.array(way)
    inner = np.column_stack([grid.qs[at // grid.us.size], grid.us[at % grid.us.size]])
    return np.vstack([ends[0], _shortened(grid, blocked, inner), ends[1]])


def _contact_overlap(setting: Setting, obj: NDArray[np.float64], poses: tuple[NDArray[np.float64], ...]
                     ) -> str | None:
    """Why a contact pose (3,) of ``poses`` makes the switch impossible (it overlaps an obstacle, or the
    object deeper than :data:`TOUCH_TOL`), or None."""
    puck = Disc(obj, setting.radius)
    for label, p in zip(("start", "end"), poses, strict=True):
        pose = Pose2D(*(float(v) for v in p))
        if pose_depth_and_gap(setting.tool, pose, puck)[0] > TOUCH_TOL:
            return f"the {label} contact pose overlaps the object (another part of the tool reaches into it)"
        for i, o in enumerate(setting.obstacles):
            if pose_depth_and_gap(setting.tool, pose, o)[0] > 0.0:
                return f"the {label} contact pose overlaps obstacle {i}"
    return None


def _off_the_omni(sector: ReachSector, pose: NDArray[np.float64], qu: NDArray[np.float64]) -> str | None:
    """Why the contact ``pose`` (3,) is no placement ``qu`` (2,) of the Omni (its heading not the Omni's, or
    its joints outside their box), or None."""
    if float(np.max(np.abs(sector.point(qu[0], qu[1]) - pose[:2]))) > 1e-9:
        return "a contact pose's heading is not the one the Omni imposes there"
    if not (sector.q1_range[0] <= qu[0] <= sector.q1_range[1] and sector.u_range[0] <= qu[1] <= sector.u_range[1]):
        return "a contact pose is outside the Omni's joints"
    return None


def grid_planner(setting: Setting, clearance: float) -> SwitchPlanner:
    """The ``grid`` switch planner in ``setting`` (module docstring): the way between the two leaving moves keeps
    ``clearance`` [m] (the task's ``ss.clearance``) from the object, on the grids of :data:`MOVES` in turn."""
    sector = reach_sector(setting.platform)
    reach = float(np.hypot(*np.asarray(setting.tool.outline.exterior.coords).T).max())

    def plan(obj: NDArray[np.float64], face_a: str, pose_a: NDArray[np.float64], face_b: str,
             pose_b: NDArray[np.float64]) -> SwitchPath:
        obj = np.asarray(obj, dtype=np.float64)
        poses = [np.asarray(p, dtype=np.float64) for p in (pose_a, pose_b)]
        ends = [placement_of(sector, p) for p in poses]
        why = next((w for p, e in zip(poses, ends, strict=True) if (w := _off_the_omni(sector, p, e)) is not None),
                   None) or _contact_overlap(setting, obj, (pose_a, pose_b))
        if why is not None:
            return SwitchPath("grid", "infeasible", f"grid switch {face_a} -> {face_b}: {why}")
        tried = []
        for move in MOVES:
            grid = _Grid(sector, reach, move)
            blocked = _blocked(setting, grid, obj, clearance)
            leave = [_leaving(setting, grid, obj, e, ~blocked) for e in ends]
            if not leave[0] or not leave[1]:
                tried.append(f"on {1e3 * move:g} mm: no straight move leaves the "
                             f"{'first' if not leave[0] else 'second'} contact pose to a free placement")
                continue
            qu = _way(grid, ends, leave, blocked)
            if qu is None:
                tried.append(f"on {1e3 * move:g} mm: no way through the free placements")
                continue
            xy, obj_check, deep_obs, gap_obs = _swept(setting, grid, obj, qu)
            deep = obj_check.max_penetration
            # the steps between the two leaving moves (each move sampled on its own by _dense)
            between = np.zeros(len(xy) - 1, dtype=bool)
            between[len(_dense(grid, qu[:2])) - 1:len(xy) - len(_dense(grid, qu[-2:]))] = True
            gap = obj_check.min_clearance(between)
            jp = joint_path(setting.platform, xy)
            if (deep <= TOUCH_TOL and gap_obs >= TOOL_MARGIN and gap >= clearance - 1e-6
                    and not jp.refused.any() and float(np.max(jp.violation)) == 0.0):
                xy[0], xy[-1] = poses[0][:2], poses[1][:2]
                return SwitchPath("grid", "solved", xy=xy, object_clearance=gap, obstacle_clearance=gap_obs,
                                  object_penetration=deep, obstacle_penetration=deep_obs,
                                  info={"move": move, "corners": len(qu)})
            tried.append(f"on {1e3 * move:g} mm: the way failed its exact check (penetration {1e3 * deep:.4f} mm, "
                         f"{1e3 * gap:.3f} mm from the object between the leaving moves, obstacles "
                         f"{1e3 * gap_obs:.3f} mm away, reach violation {float(np.max(jp.violation)):.3g} rad)")
        return SwitchPath("grid", "infeasible", f"grid switch {face_a} -> {face_b} (object at "
                          f"{np.round(obj, 4).tolist()} m, {1e3 * clearance:g} mm kept from it): " + "; ".join(tried)
                          + " (complete on its grids only, its leaving moves straight: others may find a way)")

    return plan
