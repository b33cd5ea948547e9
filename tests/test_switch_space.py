"""The tool's free placements on the Omni (verdicts/switch_space.py) against brute force and solved plans.

The brute force here places the outline with shapely on a grid of waist angles and reaches, with none of
the module's arithmetic (no rows of blocked intervals, no Minkowski differences): a placement is free
unless the outline shrunk by the most any tool point moves between neighbouring grid points meets an
obstacle or the puck. That grid's free points, joined to their eight neighbours, hold every path of the
true free space, so where it finds two contact poses in different pieces no move of the tool joins them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from scipy import ndimage
from test_verdicts import contact_pose, generated

from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import solve
from tooltransfer.planner.planning.verdicts.switch_forward import block_separated
from tooltransfer.planner.planning.verdicts.switch_space import components, placement_space
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.reach import reach_sector


def _world(task_id: str):
    task = generated("execution_60.yaml", task_id)
    return task, setting_from_task(task, task_skills(task, need_ss=False))


def _placed(base: np.ndarray, a: float, u: float, pts: np.ndarray) -> np.ndarray:
    """Points ``pts`` (V, 2) [tool frame] with the tool placed at waist angle ``a`` and reach ``u`` on the
    Omni at ``base`` (2,) [m]: origin ``base + R(a) (u, d_t)``, heading ``a - pi/2``; (V, 2) [m]."""
    yaw = a - math.pi / 2
    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    origin = base + np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]) @ np.array([u, D_TOOL])
    return pts @ rot.T + origin


def _outline_at(base: np.ndarray, a: float, u: float, ring: np.ndarray) -> shapely.Polygon:
    """The tool ``ring`` (V, 2) [tool frame] placed as :func:`_placed` places it."""
    return shapely.Polygon(_placed(base, a, u, ring))


def _outlines_along(base: np.ndarray, a: float, us: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """The tool ``ring`` (V, 2) placed as :func:`_placed` places it at waist angle ``a`` and each reach of
    ``us`` (U,) [m]: (U,) polygons, made in one call (one by one they took most of a lattice search)."""
    yaw = a - math.pi / 2
    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    arm = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    origins = np.array([base + arm @ np.array([u, D_TOOL]) for u in us])  # as _placed computes each
    return shapely.polygons((ring @ rot.T)[None, :, :] + origins[:, None, :])


def _shapes(setting, centre: np.ndarray) -> shapely.Geometry:
    """The obstacles and the puck's open disc (inscribed polygons: a shape met is met by the true one)."""
    parts = [o.polygon(256) if isinstance(o, Disc) else o for o in setting.obstacles]
    return shapely.union_all([*parts, shapely.Point(centre).buffer(setting.radius - 1e-7, quad_segs=256)])


def test_a_blocked_placement_meets_an_obstacle_or_the_puck_at_every_angle_of_its_row() -> None:
    task, setting = _world("exec60-00054")
    ps = placement_space(setting)
    centre = np.array(task.start)
    rows = ps.free_rows(centre, setting.radius)
    shapes = _shapes(setting, centre)
    ring = np.asarray(setting.tool.outline.exterior.coords)
    rng = np.random.default_rng(3)
    checked = free_checked = 0
    for k in rng.choice(ps.n_rows, 400, replace=False):
        u = float(rng.uniform(*ps.u_range))
        free = any(lo <= u <= hi for lo, hi in rows[k])
        a_mid = ps.row_angle(int(k))
        if free:  # the over-approximation is not loose: a free placement is free at the row's middle but rarely
            free_checked += 1
            continue
        for a in (a_mid - 0.5 * ps.dq, a_mid, a_mid + 0.5 * ps.dq):
            assert _outline_at(ps.base, a, u, ring).intersects(shapes), (k, u, a)
        checked += 1
    assert checked > 20 and free_checked > 20


def test_the_switch_paths_of_a_solved_plan_lie_in_one_component_with_their_contact_poses() -> None:
    task, setting = _world("exec60-00001")
    plan = solve(task)
    assert plan.status == "solved" and plan.switches
    ps = placement_space(setting)
    for sw in plan.switches:
        i0, i1 = np.searchsorted(plan.t, [sw.t_start, sw.t_end])
        centre = plan.object_xy[i0]
        rows = ps.free_rows(centre, setting.radius)
        labels = components(rows)
        on_path = set()
        for x, y, yaw in plan.tool_pose[i0:i1 + 1]:
            a = yaw + math.pi / 2
            q1 = math.remainder(a - ps.base_yaw, 2 * math.pi)
            u = (x - ps.base[0]) * math.cos(a) + (y - ps.base[1]) * math.sin(a)
            k = min(max(math.floor((q1 - ps.q1_range[0]) / ps.dq), 0), ps.n_rows - 1)
            hit = {lab for (lo, hi), lab in zip(rows[k], labels[k], strict=True) if lo - 1e-9 <= u <= hi + 1e-9}
            assert hit, f"a pose of the switch {sw.faces} is in no free interval"
            on_path |= hit
        assert len(on_path) == 1
        for face in sw.faces:
            assert on_path <= ps.contact_components(setting.tool.face(face), centre, setting.radius, rows, labels)
        assert not ps.separated(setting.tool.face(sw.faces[0]), setting.tool.face(sw.faces[1]), centre,
                                setting.radius)


def _grid_pieces(setting, centre: np.ndarray, move: float):
    """Brute force (module docstring): labels of the free points of a grid of waist angles and reaches
    whose neighbours are at most ``move`` [m] apart at any tool point, and the grid's axes. The grid spans
    the joints of the Omni's reach sector (not the placement space's copy of them)."""
    sec = reach_sector(setting.platform)
    reach = float(np.hypot(*np.asarray(setting.tool.outline.exterior.coords).T).max())
    r_max = math.hypot(sec.u_range[1] + reach, D_TOOL + reach)
    qs = np.arange(sec.q1_range[0], sec.q1_range[1] + 1e-12, move / r_max)
    us = np.arange(sec.u_range[0], sec.u_range[1] + 1e-12, move)
    shrunk = setting.tool.outline.buffer(-1.5 * move, join_style="mitre")
    ring = np.asarray(shrunk.exterior.coords)
    shapes = _shapes(setting, centre)
    shapely.prepare(shapes)
    free = np.zeros((qs.size, us.size), dtype=bool)
    for i, q in enumerate(qs):
        free[i] = ~shapely.intersects(shapes, _outlines_along(np.asarray(sec.centre), sec.base_yaw + q, us, ring))
    pieces, _ = ndimage.label(free, structure=np.ones((3, 3), dtype=int))  # 8-neighbours, as one move joins
    return pieces - 1, qs, us


def contact_poses(setting, face, centre: np.ndarray, n: int = 200) -> list[tuple[float, float, float]]:
    """``(q1, u, s)``: the waist angle [rad] about the Omni's base yaw and the reach [m] at which ``face``'s
    contact, at ``n`` places ``s`` along its range, holds the puck at ``centre`` (2,) [m], within the Omni's
    joints: worked out from the reach sector alone (``test_verdicts.contact_pose``, not the placement
    space's ``contact_places``)."""
    sec = reach_sector(setting.platform)
    centre = np.asarray(centre, dtype=np.float64)
    poses = ((contact_pose(sec, face, centre, setting.radius, s), float(s))
             for s in np.linspace(*face.contact_range, n))
    return [(pose[2], pose[1], s) for pose, s in poses if pose is not None]


def grid_holds(setting, centre: np.ndarray, faces: list[str], move: float = 6e-4) -> dict[str, set[int]]:
    """Brute force (module docstring): per face of ``faces``, the labels of the grid's free points next to any
    of its contact poses (:func:`contact_poses`) with the puck at ``centre``."""
    label, qs, us = _grid_pieces(setting, centre, move)
    out: dict[str, set[int]] = {}
    for name in faces:
        got = set()
        for q1, u, _ in contact_poses(setting, setting.tool.face(name), centre):
            i, j = np.searchsorted(qs, q1), np.searchsorted(us, u)
            got |= {int(label[a, b]) for a in (i - 1, i) for b in (j - 1, j)
                    if 0 <= a < qs.size and 0 <= b < us.size and label[a, b] >= 0}
        out[name] = got
    return out


def placement_pieces(setting, centre: np.ndarray, placements: list[tuple[float, float]], move: float = 6e-4
                     ) -> list[set[int]]:
    """Brute force (module docstring): per placement ``(q1, u)`` [rad, m] of ``placements``, the labels of the
    grid's free points next to it with the puck at ``centre`` (two placements with no label in common lie in
    different pieces: no move of the tool joins them)."""
    label, qs, us = _grid_pieces(setting, centre, move)
    out = []
    for q1, u in placements:
        i, j = np.searchsorted(qs, q1), np.searchsorted(us, u)
        out.append({int(label[a, b]) for a in (i - 1, i) for b in (j - 1, j)
                    if 0 <= a < qs.size and 0 <= b < us.size and label[a, b] >= 0})
    return out


def grid_separated(setting, face_a, face_b, centre: np.ndarray, move: float = 6e-4) -> bool:
    """Brute force (module docstring): whether the grid's free points next to the contact poses of
    ``face_a`` and of ``face_b`` with the puck at ``centre`` lie in different pieces (False where either
    face has none: nothing to separate)."""
    held = grid_holds(setting, centre, [face_a.name, face_b.name], move)
    a, b = held[face_a.name], held[face_b.name]
    return bool(a) and bool(b) and not (a & b)


@pytest.mark.parametrize(("where", "faces", "apart"), [
    ((-0.016, 0.008), ("foot_top", "left"), True),   # the l_shape's foot cannot get round the puck to its left face
    ((0.0, 0.0), ("top", "left"), False),
])
def test_separated_agrees_with_a_brute_force_grid(where, faces, apart) -> None:
    task, setting = _world("exec60-00054")
    ps = placement_space(setting)
    centre = np.array(task.start) + np.array(where)
    fa, fb = (setting.tool.face(f) for f in faces)
    if not apart:  # the puck at the target: both faces reach it
        centre = np.array(task.target)
    assert ps.separated(fa, fb, centre, setting.radius) is apart
    held = grid_holds(setting, centre, list(faces))
    a, b = held[faces[0]], held[faces[1]]
    assert a and b
    assert (not (a & b)) is apart


def test_the_independent_contact_poses_hold_the_puck_and_match_the_placement_space() -> None:
    """:func:`contact_poses` puts each face's contact on the puck: the tool placed at the pose (as the
    brute-force grid places it) carries the contact point, the face's point pushed out by the radius, to
    the puck's centre; and the placement space's own poses (``contact_places``, the certificate's) are the
    same poses."""
    task, setting = _world("exec60-00054")
    ps = placement_space(setting)
    centre = np.array(task.start) + np.array((-0.016, 0.008))
    sec = reach_sector(setting.platform)
    for face in setting.tool.faces:
        mine = contact_poses(setting, face, centre, n=25)
        for q1, u, s in mine:
            c = face.point(s) + setting.radius * face.normal
            assert np.allclose(_placed(np.asarray(sec.centre), sec.base_yaw + q1, u, c[None, :])[0], centre,
                               atol=1e-12)
        theirs = [(q, u) for q, u, _, _ in ps.contact_places(face, centre, setting.radius, n=25)
                  if sec.q1_range[0] <= q <= sec.q1_range[1] and sec.u_range[0] <= u <= sec.u_range[1]]
        assert np.allclose(np.array(theirs).reshape(-1, 2), np.array([m[:2] for m in mine]).reshape(-1, 2),
                           atol=1e-12)


def test_a_pair_block_separated_calls_apart_is_apart_for_the_brute_force_across_the_block() -> None:
    """``block_separated`` claims its pairs have no switch for a puck anywhere in the block (a 5 mm block,
    as the certificate's sets use on 2.5 mm cells): the brute-force grid, at the block's corners, middle and
    two random points, never joins a claimed pair's contact poses (and it does find poses of both faces of
    the pair the test is about, so the check is not empty)."""
    task, setting = _world("exec60-00054")
    ps = placement_space(setting)
    mid = np.array(task.start) + np.array((-0.016, 0.008))
    h = 0.0025
    box = (mid[0] - h, mid[1] - h, mid[0] + h, mid[1] + h)
    names = [f.name for f in setting.tool.faces]
    cut = block_separated(ps, names, box, setting.radius)
    assert ("foot_top", "left") in cut
    rng = np.random.default_rng(11)
    inset = h - 1e-6
    points = [mid + np.array(c) for c in ((-inset, -inset), (-inset, inset), (inset, -inset), (inset, inset),
                                          (0.0, 0.0))]
    points += [mid + rng.uniform(-inset, inset, 2) for _ in range(2)]
    both = 0
    for p in points:
        held = grid_holds(setting, p, names)
        for g, f in cut:
            assert not (held[g] & held[f]), (g, f, p)
        both += bool(held["foot_top"] and held["left"])
    assert both == len(points)
