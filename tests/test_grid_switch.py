"""The ``grid`` switch planner (planning/ss/grid_variant.py): it finds the switches the ``arch`` reference gives
up on, its paths hold the planner's rules when checked by this file's own kinematics and geometry, and it
refuses where the brute-force grid of ``test_switch_space`` separates the two contact poses.

The check here places the tool with the Omni's waist and reach worked out from the reach sector alone
(``test_verdicts.contact_pose``'s arithmetic, inverted for a tool origin), not with the module's code.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import shapely
from test_switch_space import _placed, placement_pieces
from test_verdicts import contact_pose, generated

import tooltransfer.planner.planning.variant_registry as reg
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.ss.grid_variant import LEAVE_REACH, grid_planner
from tooltransfer.planner.planning.switches import arch_planner
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN
from tooltransfer.problems.task import SSOptions
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.reach import reach_sector


def _world(task_id: str):
    task = generated("execution_60.yaml", task_id)
    return task, setting_from_task(task, task_skills(task, need_ss=False))


def _pose(sec, face, centre: np.ndarray, radius: float, s: float) -> np.ndarray:
    """The tool pose ``(x, y, yaw)`` at which ``face``'s contact at ``s`` holds the puck at ``centre``."""
    got = contact_pose(sec, face, centre, radius, s)
    assert got is not None
    a, u, _ = got
    origin = _placed(np.asarray(sec.centre), a, u, np.zeros((1, 2)))[0]
    return np.array([origin[0], origin[1], a - math.pi / 2])


def _joints(sec, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Waist angles ``a`` (K,) [rad] and reaches ``u`` (K,) [m] putting the tool origin at ``xy`` (K, 2):
    ``xy = base + R(a) (u, d_t)`` solved for ``a`` and ``u`` (``u > 0``)."""
    d = xy - np.asarray(sec.centre)
    r = np.hypot(d[:, 0], d[:, 1])
    u = np.sqrt(r * r - D_TOOL * D_TOOL)
    a = np.arctan2(d[:, 1], d[:, 0]) - np.arctan2(D_TOOL, u)
    return a, u


def _check_path(setting, centre: np.ndarray, xy: np.ndarray, pose_a: np.ndarray, pose_b: np.ndarray,
                clearance: float) -> None:
    """The switch path ``xy`` (K, 2) [m] holds the rules, checked here at its samples: it starts and ends at the
    contact poses; every sample is within the Omni's joints; no tool point moves more than 0.3 mm between
    samples; the outline never enters the puck by more than 10 um (the hard check's bound; the two contacts
    touch it) nor comes within ``TOOL_MARGIN`` of an obstacle; it keeps ``clearance`` [m] from the puck but along
    the leaving moves next to either end (:data:`LEAVE_REACH` in the placements' metric; the tool's origin moves
    at most sqrt(2) times that), and gets that far from it."""
    sec = reach_sector(setting.platform)
    assert np.allclose(xy[0], pose_a[:2], atol=1e-12) and np.allclose(xy[-1], pose_b[:2], atol=1e-12)
    a, u = _joints(sec, xy)
    q1 = np.remainder(a - sec.base_yaw + math.pi, 2 * math.pi) - math.pi
    assert np.all((q1 >= sec.q1_range[0]) & (q1 <= sec.q1_range[1]))
    assert np.all((u >= sec.u_range[0]) & (u <= sec.u_range[1]))
    ring = np.asarray(setting.tool.outline.exterior.coords)
    placed = [_placed(np.asarray(sec.centre), float(ak), float(uk), ring) for ak, uk in zip(a, u, strict=True)]
    moves = [float(np.max(np.hypot(*(q - p).T))) for p, q in itertools.pairwise(placed)]
    assert max(moves) <= 3e-4
    outlines = shapely.polygons(np.array(placed))
    gap = shapely.distance(outlines, shapely.Point(centre)) - setting.radius  # exact: 0 - r inside the outline
    assert gap.min() >= -1e-5
    for o in setting.obstacles:
        near = (shapely.distance(outlines, shapely.Point(o.centre)) - o.radius if isinstance(o, Disc)
                else shapely.distance(outlines, o))
        assert near.min() >= TOOL_MARGIN - 1e-9
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    from_end = np.minimum(along, along[-1] - along)
    assert np.all(from_end[gap < clearance - 1e-6] <= math.sqrt(2) * LEAVE_REACH)
    assert gap.max() >= clearance - 1e-6


@pytest.mark.parametrize(("task_id", "where", "faces"), [
    ("exec60-00054", (-0.1052, 0.0988), ("foot_top", "top")),
    ("exec60-00012", (0.1249, 0.1272), ("inclined", "left")),
])
def test_the_grid_finds_a_switch_the_arch_gives_up_on_and_its_path_holds_the_rules(task_id, where, faces) -> None:
    """Next to the Omni's inner reach, ``arch`` backs off out of reach; the grid goes round within it."""
    task, setting = _world(task_id)
    sec = reach_sector(setting.platform)
    centre = np.array(where)
    fa, fb = (setting.tool.face(f) for f in faces)
    pa, pb = (_pose(sec, f, centre, setting.radius, float(np.mean(f.contact_range))) for f in (fa, fb))
    arch = arch_planner(setting, task.ss.clearance)(centre, fa.name, pa, fb.name, pb)
    assert arch.status == "infeasible" and "out of reach" in arch.reason
    found = grid_planner(setting, task.ss.clearance)(centre, fa.name, pa, fb.name, pb)
    assert found.status == "solved", found.reason
    _check_path(setting, centre, found.xy, pa, pb, task.ss.clearance)
    assert found.object_penetration <= 1e-5 and found.obstacle_clearance >= TOOL_MARGIN
    assert found.object_clearance >= task.ss.clearance - 1e-6


def test_the_grid_refuses_a_switch_the_brute_force_grid_separates() -> None:
    """The puck where the l_shape's foot cannot get round it to its left face (``test_switch_space``): the grid
    finds no way, and says it is complete on its grids only; the brute-force grid puts the two poses in
    different pieces."""
    task, setting = _world("exec60-00054")
    sec = reach_sector(setting.platform)
    centre = np.array(task.start) + np.array((-0.016, 0.008))
    fa, fb = setting.tool.face("foot_top"), setting.tool.face("left")
    pa, pb = _pose(sec, fa, centre, setting.radius, 0.52), _pose(sec, fb, centre, setting.radius, 0.0)
    found = grid_planner(setting, task.ss.clearance)(centre, fa.name, pa, fb.name, pb)
    assert found.status == "infeasible" and "no way through the free placements" in found.reason
    assert "complete on its grids only" in found.reason
    placements = []
    for face, s in ((fa, 0.52), (fb, 0.0)):
        _, u, q1 = contact_pose(sec, face, centre, setting.radius, s)
        placements.append((q1, u))
    pieces = placement_pieces(setting, centre, placements)
    assert pieces[0] and pieces[1] and not pieces[0] & pieces[1]


def test_a_contact_pose_in_an_obstacle_is_refused_before_any_search() -> None:
    """A small square laid over the tool's farthest point at the first contact pose: no switch can start
    there, and the planner says why without searching."""
    task, setting = _world("exec60-00054")
    sec = reach_sector(setting.platform)
    centre = np.array((-0.1052, 0.0988))
    fa, fb = setting.tool.face("foot_top"), setting.tool.face("top")
    pa, pb = (_pose(sec, f, centre, setting.radius, float(np.mean(f.contact_range))) for f in (fa, fb))
    a, u = _joints(sec, pa[None, :2])
    ring = _placed(np.asarray(sec.centre), float(a[0]), float(u[0]), np.asarray(setting.tool.outline.exterior.coords))
    tip = ring[np.argmax(np.hypot(*(ring - centre).T))]
    square = shapely.box(*(tip - 0.002), *(tip + 0.002))
    walled = replace(setting, obstacles=(*setting.obstacles, square))
    found = grid_planner(walled, task.ss.clearance)(centre, fa.name, pa, fb.name, pb)
    assert found.status == "infeasible"
    assert f"the start contact pose overlaps obstacle {len(setting.obstacles)}" in found.reason


def test_opt_falls_back_to_the_arch_then_to_the_grid() -> None:
    """The registry's chain: where the ``opt`` NLP (local) and ``arch`` find no path, the grid's is taken,
    marked a fallback."""
    task, setting = _world("exec60-00012")
    skill = task_skills(task).ss
    sec = reach_sector(setting.platform)
    centre = np.array((0.1249, 0.1272))
    fa, fb = setting.tool.face("inclined"), setting.tool.face("left")
    pa, pb = (_pose(sec, f, centre, setting.radius, float(np.mean(f.contact_range))) for f in (fa, fb))
    alone = reg.switch_planner("opt", setting, skill, SSOptions())
    chain = reg.ss_variant("opt")
    first = chain.planner(setting, skill, SSOptions())(centre, fa.name, pa, fb.name, pb)
    assert first.status != "solved"
    found = alone(centre, fa.name, pa, fb.name, pb)
    assert found.status == "solved" and found.variant == "grid" and found.fallback
    _check_path(setting, centre, found.xy, pa, pb, SSOptions().clearance)


def test_the_switch_benchmark_runs_and_prints_both_chains(capsys) -> None:
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import bench_switch_grid

    assert bench_switch_grid.main(["--tasks", "1", "--per-task", "2", "--seed", "5"]) == 0
    out = capsys.readouterr().out
    assert "switches on 1 tasks (seed 5)" in out
    assert "opt -> arch (before)" in out and "opt -> arch -> grid (now)" in out
