"""Verdicts: certificates are checked again, replayed against an independent lattice search, never
issued where the planner finds a plan, and carried by the plan file and the command line.

The lattice search here is this file's own code, not the project's: from the start it pushes the
puck in straight steps of a few millimetres in directions sampled in each face's cone, with the face
held where the Omni can hold it (waist, reach, contact on the face's range, computed from the
kinematics), the puck clear of the obstacles by the margin and the tool's outline clear of them. Its steps
are pushes where they start (with ``ends_held``, held where they end too: a step from the edge of a
face's reach may otherwise end where no face holds the puck), so on a task with a certificate it must
not come near the target, and its positions must not enter the certificate's set.
"""

from __future__ import annotations

import json
import math
from collections import deque
from pathlib import Path

import numpy as np
import pytest
import shapely

from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.solve import solve
from tooltransfer.planner.planning.verdicts.bounds import direction_arcs, push_space
from tooltransfer.planner.planning.verdicts.certificate import certify, check_certificate
from tooltransfer.planner.planning.verdicts.rules import setting_rules
from tooltransfer.problems.task import load_task
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.reach import reach_sector

ROOT = Path(__file__).resolve().parents[1]
CERTIFIED = ("hard/only_face_pushes_away.yaml", "hard/target_out_of_reach.yaml")


def _rules_of(task):
    s = setting_from_task(task, task_skills(task, need_ss=False))
    return s, setting_rules(s)


def contact_pose(sec, face, p: np.ndarray, radius: float, s: float) -> tuple[float, float, float] | None:
    """``(a, u, q1)``: the waist angle [rad] (world), the arm-plane reach [m] and the waist about the Omni's
    base yaw [rad] at which ``face``'s contact at ``s`` of its range holds the puck (``radius`` [m]) at
    ``p`` (2,) [m], worked out from the reach sector ``sec`` alone; None outside the Omni's joints."""
    d = p - sec.centre
    r = math.hypot(*d)
    c = face.point(s) + radius * face.normal
    o = D_TOOL - c[0]
    if r <= abs(o):
        return None
    v = math.sqrt(r * r - o * o)
    u = v - c[1]
    a = math.atan2(d[1], d[0]) - math.atan2(o, v)
    q1 = math.remainder(a - sec.base_yaw, 2 * math.pi)
    if not (sec.u_range[0] <= u <= sec.u_range[1] and sec.q1_range[0] <= q1 <= sec.q1_range[1]):
        return None
    return a, u, q1


def _holds(tool: Tool, face, platform, p: np.ndarray, radius: float, obstacles: list, contacts: int = 7,
           room: float = 0.0) -> list[float]:
    """The tool yaws [rad] at which ``face`` can push the puck at ``p`` (contact sampled at ``contacts``
    places along the face's range): waist and reach within the limits (:func:`contact_pose`), the outline
    clear of the obstacles (farther than ``room`` [m] from them)."""
    sec = reach_sector(platform)
    yaws = []
    for s in np.linspace(*face.contact_range, contacts):
        pose = contact_pose(sec, face, p, radius, s)
        if pose is None:
            continue
        c = face.point(s) + radius * face.normal
        yaw = pose[0] - math.pi / 2
        rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
        outline = shapely.Polygon((np.asarray(tool.outline.exterior.coords) - c) @ rot.T + p)
        if all(shapely.distance(outline, o.polygon() if isinstance(o, Disc) else o) > room for o in obstacles):
            yaws.append(yaw)
    return yaws


def _cone(face, half: float) -> tuple[float, float]:
    """``(lo, hi)`` [rad]: the directions ``face`` pushes in, about its normal, within the friction cone's
    ``half``-angle and its tool file's ``push_angle +- theta_b`` (empty where ``hi < lo``)."""
    off = math.remainder(face.push_angle - face.normal_angle, 2 * math.pi)
    return max(-half, off - face.theta_b), min(half, off + face.theta_b)


def _edges_first(angles: np.ndarray) -> np.ndarray:
    """``angles`` with the cone's two edges first: a step that ends in a cell already visited is dropped,
    and of two neighbouring steps of one yaw ending in one cell the edge's is kept (another yaw's or face's
    step may still take the cell first), without which a path along a cone's edge (a shallow way round an
    obstacle) is lost cell by cell."""
    return np.concatenate([angles[[0, -1]], angles[1:-1]]) if angles.size >= 3 else angles


def lattice_search(setting, start: np.ndarray, target: np.ndarray, *, step: float = 0.003,
                   cell: float = 0.0015, budget: int = 4000, directions: int = 5, contacts: int = 7,
                   yaw_stride: int = 3, ends_held: bool = False, visited: list | None = None,
                   share: float = 1.0, room: float = 0.0) -> float:
    """The closest the puck comes to ``target`` [m] by straight pushes from ``start`` (breadth first,
    one visit per lattice cell of side ``cell``, at most ``budget`` expansions): steps of ``step`` [m] in
    ``directions`` directions across each face's cone, from every ``yaw_stride``-th of the yaws at which
    the face holds the puck with the contact at ``contacts`` places of its range, the cone's edges first
    (:func:`_edges_first`); with ``ends_held`` only steps whose end the face can still hold (a push holds
    the puck all along; a step from the edge of a face's reach otherwise ends outside it). A denser search
    (``benchmarks/check_certificates.py --dense``) takes more of each. ``visited``: a list the positions
    (2,) [m] the search reaches are appended to, the start first. ``share`` of the friction cone's
    half-angle and ``room`` [m] kept between the tool outline and the obstacles: 1 and 0 search under the
    certificates' rules; less and more, under rules with margins a plan could keep (``--unknowns``)."""
    tool, radius = setting.tool, setting.radius
    obstacles = [o.polygon() if isinstance(o, Disc) else o for o in setting.obstacles]  # made once, not per step
    clear = radius + setting.margin - 1e-5
    mu_half = share * math.atan(setting.mechanics.mu)
    frontier, seen = deque([start]), {tuple(np.floor(start / cell).astype(int))}
    best, n = float(np.hypot(*(start - target))), 0
    yaws_at: dict[tuple[str, bytes], list[float]] = {}  # a step's end held (ends_held), then expanded

    def holds(face, p: np.ndarray) -> list[float]:
        key = (face.name, p.tobytes())
        if key not in yaws_at:
            yaws_at[key] = _holds(tool, face, setting.platform, p, radius, obstacles, contacts, room)
        return yaws_at[key]

    if visited is not None:
        visited.append(np.asarray(start, dtype=float))
    while frontier and n < budget:
        p = frontier.popleft()
        n += 1
        for face in tool.faces:
            lo, hi = _cone(face, mu_half)
            if hi < lo:
                continue
            for yaw in holds(face, p)[::yaw_stride]:
                for ang in _edges_first(np.linspace(lo, hi, directions)):
                    w = yaw + face.normal_angle + ang
                    q = p + step * np.array([math.cos(w), math.sin(w)])
                    key = tuple(np.floor(q / cell).astype(int))
                    if key in seen:
                        continue
                    if any(shapely.distance(shapely.Point(q), o) < clear for o in obstacles):
                        continue
                    if ends_held and not holds(face, q):
                        continue
                    seen.add(key)
                    frontier.append(q)
                    if visited is not None:
                        visited.append(q)
                    best = min(best, float(np.hypot(*(q - target))))
    return best


def depth_inside(region: shapely.Geometry, points: np.ndarray) -> float:
    """How deep [m] the deepest of ``points`` (N, 2) [m] lies inside ``region`` (0 where none is inside)."""
    at = shapely.points(points)
    inside = shapely.contains(region, at)
    return float(shapely.distance(shapely.boundary(region), at[inside]).max()) if inside.any() else 0.0


def generated(batch_file: str, task_id: str):
    """The task ``task_id`` of the committed batch file ``problems/batch/<batch_file>``, as generated."""
    from tooltransfer.planner.apps.batch.generate import generate_tasks
    from tooltransfer.planner.apps.batch.spec import load_batch
    from tooltransfer.problems.task import task_from_dict

    batch = ROOT / "problems" / "batch" / batch_file
    data = next(g.data for g in generate_tasks(load_batch(batch), batch) if g.task_id == task_id)
    return task_from_dict(data, str(batch))


@pytest.mark.parametrize("name", CERTIFIED)
def test_certificate_holds_when_checked_again_and_the_lattice_search_finds_nothing(name: str) -> None:
    task = load_task(ROOT / "problems" / name)
    setting, rules = _rules_of(task)
    cert, why = certify(rules, np.array(task.start), np.array(task.target))
    assert cert is not None, why
    assert check_certificate(cert, rules) == []
    closest = lattice_search(setting, np.array(task.start), np.array(task.target))
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"


def test_a_generated_task_with_an_obstacle_certified_and_the_lattice_search_finds_nothing() -> None:
    """An obstacle case of the execution benchmark's batch: the tool body's zone takes part."""
    task = generated("execution_60.yaml", "exec60-00031")
    setting, rules = _rules_of(task)
    cert, why = certify(rules, np.array(task.start), np.array(task.target))
    assert cert is not None and cert.kind == "backward_reachable", why
    assert check_certificate(cert, rules) == []
    closest = lattice_search(setting, np.array(task.start), np.array(task.target))
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"
    # and no position a search with held ends reaches lies inside the certificate's set (a step of 3 mm
    # along a cone's edge may cut its boundary by hundredths of a millimetre)
    visited: list = []
    lattice_search(setting, np.array(task.start), np.array(task.target), ends_held=True, visited=visited)
    assert len(visited) > 100
    assert depth_inside(cert.region, np.asarray(visited)) < 5e-4


def test_a_certificate_on_the_finest_grid_and_the_lattice_search_finds_nothing() -> None:
    """An execution-benchmark task (slope tool, one obstacle) whose set reaches the start on 10 mm and
    5 mm cells: on 2.5 mm cells each face's cone turns by less over a block and the set leaves the start
    out; the check replays it block by block and the lattice search stays away from the target."""
    task = generated("execution_60.yaml", "exec60-00016")
    setting, rules = _rules_of(task)
    for coarser in ((0.01,), (0.01, 0.005)):
        cert, why = certify(rules, np.array(task.start), np.array(task.target), h=coarser)
        assert cert is None and "came within the gap of the start" in why
    cert, why = certify(rules, np.array(task.start), np.array(task.target))
    assert cert is not None and cert.kind == "backward_reachable" and cert.grid is not None, why
    assert cert.grid.h == pytest.approx(0.0025)
    assert check_certificate(cert, rules) == []
    closest = lattice_search(setting, np.array(task.start), np.array(task.target))
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"


def test_a_certificate_on_the_finer_grid_and_the_lattice_search_finds_nothing() -> None:
    """A finger task round an obstacle (from a seed no project file uses): 10 mm cells cut the corner
    round the obstacle and reach the start; 5 mm cells leave it out, and the check holds."""
    task = _round_the_obstacle()
    setting, rules = _rules_of(task)
    cert, why = certify(rules, np.array(task.start), np.array(task.target))
    assert cert is not None and cert.kind == "backward_reachable" and cert.grid is not None, why
    assert cert.grid.h == pytest.approx(0.005)  # the finer grid, tried only where 10 mm cells reach the start
    assert check_certificate(cert, rules) == []
    closest = lattice_search(setting, np.array(task.start), np.array(task.target))
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"


def _round_the_obstacle():
    from tooltransfer.problems.task import task_from_dict

    data = {"format": "tooltransfer.task/1", "tool": "finger",
            "skills": {"dataset": str(ROOT / "problems" / "data" / "finger_demos")},
            "name": "round_the_obstacle", "start": [0.088601, 0.136626], "target": [0.022829, 0.175063],
            "obstacles": [{"kind": "polygon", "vertices": [[0.077844, 0.166433], [0.072647, 0.169323],
                                                           [0.068293, 0.165272], [0.070799, 0.15988],
                                                           [0.076702, 0.160598]]}]}
    return task_from_dict(data, "round_the_obstacle")


def test_a_tampered_certificate_fails_its_check() -> None:
    """A backward set grown on the start's side of the polar invariant (the finger's faces all lean the
    puck one way round the Omni's axis): a shrunk set, a set holding the start and a tampered invariant
    are refused."""
    task = _round_the_obstacle()
    _, rules = _rules_of(task)
    cert, _ = certify(rules, np.array(task.start), np.array(task.target))
    assert cert is not None and cert.kind == "backward_reachable" and cert.region is not None
    assert "invariant" in cert.extra and check_certificate(cert, rules) == []
    region, inv = cert.region, cert.extra["invariant"]
    cert.region = shapely.buffer(region, -0.002)
    problems = check_certificate(cert, rules)
    assert problems and any("not closed" in p or "goal" in p for p in problems)
    cert.region = shapely.box(-1, -1, 1, 1)
    assert any("start" in p for p in check_certificate(cert, rules))
    cert.region, cert.extra = region, {**cert.extra, "invariant": dict(inv, slopes=[-m for m in inv["slopes"]])}
    assert any("not allowed" in p for p in check_certificate(cert, rules))


def test_a_solved_task_gets_no_certificate_and_its_path_obeys_the_rules() -> None:
    """The over-approximation holds the planner's own plan: every object position of a push lies in the
    push space, and every step of it in a direction its box allows."""
    task = load_task(ROOT / "problems" / "paper" / "transfer_tool2.yaml")
    plan = solve(task)
    assert plan.status == "solved" and plan.evidence["verdict"] == "solved"
    _, rules = _rules_of(task)
    cert, why = certify(rules, np.array(task.start), np.array(task.target))
    assert cert is None and why
    space = push_space(rules)
    pushing = np.array([ph == "push" for ph in plan.phase])
    xy = plan.object_xy
    assert all(shapely.distance(space, shapely.Point(p)) < 1e-6 for p in xy[pushing])
    for k in np.flatnonzero(pushing[:-1] & pushing[1:]):
        d = xy[k + 1] - xy[k]
        if np.hypot(*d) < 1e-6:
            continue
        box = (*np.minimum(xy[k], xy[k + 1]) - 1e-4, *np.maximum(xy[k], xy[k + 1]) + 1e-4)
        arcs = direction_arcs(rules, box)
        ang = math.atan2(d[1], d[0])
        assert arcs is None or any(math.remainder(ang - lo, 2 * math.pi) % (2 * math.pi) <= hi - lo + 1e-3
                                   for lo, hi in arcs), f"sample {k}: direction {ang:.3f} outside {arcs}"


def test_solve_gives_each_verdict_its_status_exit_code_and_evidence(tmp_path: Path, capsys) -> None:
    out = tmp_path / "plan.json"
    assert main(["solve", str(ROOT / "problems" / "hard" / "target_out_of_reach.yaml"), "--json", "-o", str(out)]) == 1
    summary = json.loads(capsys.readouterr().out)
    assert summary["status"] == "infeasible" and summary["evidence"] == "target_unpushable"
    doc = json.loads(out.read_text())
    assert doc["verdict"] == "infeasible" and doc["evidence"]["certificate"]["kind"] == "target_unpushable"
    from tooltransfer.planner.planning.plan import read_plan

    assert read_plan(out).evidence["kind"] == "target_unpushable"
    code = main(["solve", str(ROOT / "problems" / "hard" / "target_at_edge_of_reach.yaml"), "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert (code, summary["status"], summary["evidence"]) == (3, "unknown", "search_exhausted")
    assert "not proved infeasible" in summary["reason"]


def test_solve_budget_is_recorded_and_checked(tmp_path: Path, capsys) -> None:
    """``solve --budget K`` plans with K times the search's and the certificate's budgets and records K in
    the verdict's evidence; a budget below 1 is bad input (exit 2, naming the option)."""
    out = tmp_path / "plan.json"
    assert main(["solve", "paper/transfer_tool2", "--budget", "2", "-o", str(out)]) == 0
    assert json.loads(out.read_text())["evidence"]["budget"] == 2.0
    capsys.readouterr()
    assert main(["solve", "paper/transfer_tool2", "--budget", "0.5"]) == 2
    assert "--budget" in capsys.readouterr().err


def test_the_lattice_search_keeps_the_margins_it_is_given() -> None:
    """``share`` and ``room`` narrow the lattice search's rules (``check_certificates.py --unknowns``): with
    the tool kept a metre from the obstacles no face holds the puck anywhere near one, and the puck stays at
    the start; with the whole cone and no room the same task's search moves it."""
    task = generated("execution_60.yaml", "exec60-00031")
    setting, _ = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    still = float(np.hypot(*(start - target)))
    visited: list = []
    assert lattice_search(setting, start, target, budget=300, room=1.0, visited=visited) == still
    assert len(visited) == 1
    assert lattice_search(setting, start, target, budget=300) < still - 0.01
    assert lattice_search(setting, start, target, budget=300, room=0.0005) < still - 0.01

    def steps(share: float) -> np.ndarray:
        """The directions [rad] of the first steps from the start (one expansion) at ``share``."""
        out: list = []
        lattice_search(setting, start, target, budget=1, share=share, visited=out)
        d = np.asarray(out[1:]) - start
        return np.arctan2(d[:, 1], d[:, 0])

    def inside(w: float, share: float) -> bool:
        """Whether direction ``w`` [rad] lies in some face's cone at ``share`` from a yaw that holds the start."""
        mu = share * math.atan(setting.mechanics.mu)
        for face in setting.tool.faces:
            lo, hi = _cone(face, mu)
            for yaw in _holds(setting.tool, face, setting.platform, start, setting.radius, list(setting.obstacles)):
                a = math.remainder(w - yaw - face.normal_angle, 2 * math.pi)
                if lo - 1e-9 <= a <= hi + 1e-9:
                    return True
        return False

    narrow, wide = steps(0.3), steps(1.0)
    assert len(narrow) > 0 and all(inside(w, 0.3) for w in narrow)
    assert any(not inside(w, 0.3) for w in wide)  # the whole cone steps where 0.3 of it does not


def test_check_certificates_refuses_margins_on_certificates(capsys, monkeypatch) -> None:
    """A certificate is checked under its own rules: ``--share`` and ``--room`` only describe unknowns."""
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    import check_certificates

    for extra in (["--share", "0.9"], ["--room", "0.001"], ["--unknowns", "--share", "0"]):
        with pytest.raises(SystemExit) as err:
            check_certificates.main(["results.json", *extra])
        assert err.value.code == 2
    assert "--share" in capsys.readouterr().err
    # the whole cone and no room are the certificates' own rules: accepted (then the missing file is read)
    capsys.readouterr()
    assert check_certificates.main(["no-such-results.json", "--share", "1.0", "--room", "0"]) == 2
    assert "no-such-results.json: not a bench_verdicts.py --json file" in capsys.readouterr().err
    # a wider goal disc remakes certificates: a radius in metres, not with --unknowns
    for extra in (["--goal-disc", "0"], ["--goal-disc", "3"], ["--goal-disc", "0.001", "--unknowns"]):
        with pytest.raises(SystemExit) as err:
            check_certificates.main(["results.json", *extra])
        assert err.value.code == 2
    assert "--goal-disc" in capsys.readouterr().err


def test_check_certificates_makes_a_certificate_again_with_a_wider_goal_disc(monkeypatch) -> None:
    """``--goal-disc``: the verdict's attempts with the goal disc widened; none where it holds the start."""
    monkeypatch.syspath_prepend(str(ROOT / "benchmarks"))
    import check_certificates

    task = load_task(ROOT / "problems" / "hard" / "target_out_of_reach.yaml")
    setting, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    assert check_certificates._made_with_goal(setting, rules, start, target, 0.001) == "target_unpushable"
    wider = float(np.hypot(*(start - target))) + 0.001  # the start inside the goal disc: nothing to prove
    assert check_certificates._made_with_goal(setting, rules, start, target, wider) is None
