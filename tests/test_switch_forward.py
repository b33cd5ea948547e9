"""The ``switch_separated`` certificate (verdicts/switch_forward.py) made, replayed and checked by an
independent search whose face changes need a way for the tool found by brute force."""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import shapely
from test_switch_space import grid_separated
from test_verdicts import _cone, _edges_first, _holds, generated

from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.verdicts.backward import BlockGrid
from tooltransfer.planner.planning.verdicts.certificate import (
    Certificate,
    certify,
    certify_switches,
    check_certificate,
)
from tooltransfer.planner.planning.verdicts.rules import setting_rules
from tooltransfer.planner.planning.verdicts.switch_space import placement_space
from tooltransfer.tools.objects import Disc


def switch_lattice_search(setting, start: np.ndarray, target: np.ndarray, *, step: float = 0.003,
                          cell: float = 0.0015, budget: int = 6000, visited: list | None = None
                          ) -> tuple[float, int, bool]:
    """``(closest [m], switches refused, space exhausted)``: the test suite's lattice search
    (``test_verdicts.lattice_search``: 3 mm straight pushes across each face's whole cone from every third
    yaw the face holds the puck at, ends held, the puck its clearance from the obstacles) on states of a
    cell and the face in contact, the face changed at a node only where the brute-force grid of
    ``test_switch_space`` joins the two faces' contact poses round the resting puck. ``visited``: a list the
    positions (2,) [m] reached are appended to."""
    tool, radius = setting.tool, setting.radius
    obstacles = [o.polygon() if isinstance(o, Disc) else o for o in setting.obstacles]
    clear = radius + setting.margin - 1e-5
    mu_half = math.atan(setting.mechanics.mu)
    faces = [f for f in tool.faces if _cone(f, mu_half)[0] <= _cone(f, mu_half)[1]]
    memo: dict = {}

    def holds(face, p):
        key = (face.name, p.tobytes())
        if key not in memo:
            memo[key] = _holds(tool, face, setting.platform, p, radius, obstacles, 7, 0.0)
        return memo[key]

    def key_of(p, face):
        return (*np.floor(p / cell).astype(int), face.name)

    todo = deque((start, f) for f in faces if holds(f, start))
    seen = {key_of(start, f) for _, f in todo}
    best, n, refused = float(np.hypot(*(start - target))), 0, 0
    while todo and n < budget:
        p, face = todo.popleft()
        n += 1
        lo, hi = _cone(face, mu_half)
        for yaw in holds(face, p)[::3]:
            for ang in _edges_first(np.linspace(lo, hi, 5)):
                w = yaw + face.normal_angle + ang
                q = p + step * np.array([math.cos(w), math.sin(w)])
                k = key_of(q, face)
                if k in seen or any(shapely.distance(shapely.Point(q), o) < clear for o in obstacles):
                    continue
                if not holds(face, q):
                    continue
                seen.add(k)
                todo.append((q, face))
                best = min(best, float(np.hypot(*(q - target))))
                if visited is not None:
                    visited.append(q)
        for g in faces:
            k = key_of(p, g)
            if g is face or k in seen or not holds(g, p):
                continue
            if grid_separated(setting, face, g, p):
                refused += 1
                continue
            seen.add(k)
            todo.append((p, g))
    return best, refused, not todo


def test_a_task_whose_only_way_needs_a_switch_the_tool_cannot_make_is_certified_and_checked() -> None:
    """``exec60-00054`` (l_shape, one obstacle): only ``left`` holds the puck at the start, and it cannot push
    it to the target alone; the switch to ``foot_top`` it would need has no way round the puck (the
    planner's switch NLP and its arch fallback both fail there too)."""
    task = generated("execution_60.yaml", "exec60-00054")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    rules, space = setting_rules(setting), placement_space(setting)
    start, target = np.array(task.start), np.array(task.target)
    assert certify(rules, start, target)[0] is None  # switches free: nothing is proved
    cert, why = certify_switches(rules, space, start, target)
    assert cert is not None and cert.kind == "switch_separated", why
    assert cert.extra["holders"] == ["left"]
    assert check_certificate(cert, rules, space) == []
    assert "placement space is needed" in check_certificate(cert, rules)[0]
    other = generated("execution_60.yaml", "exec60-00020")  # the finger: another tool's placements
    finger = placement_space(setting_from_task(other, task_skills(other, need_ss=False)))
    assert "another tool or Omni" in check_certificate(cert, rules, finger)[0]
    # a grid that does not cover the push space (blocks outside it would go unchecked): refused
    h = cert.grid.h
    small = BlockGrid((cert.grid.origin[0] + 3 * h, cert.grid.origin[1] + 3 * h), h,
                      (cert.grid.shape[0] - 6, cert.grid.shape[1] - 6))
    forged = Certificate(**{**cert.__dict__, "grid": small})
    assert "does not cover" in check_certificate(forged, rules, space)[0]
    # the stored sets, with the target added to one: refused
    data = cert.to_dict()
    assert data["kind"] == "switch_separated" and set(data["regions_wkt"]) == {f.name for f in setting.tool.faces}
    bad = cert.extra | {"regions_wkt": {**cert.extra["regions_wkt"],
                                        "left": shapely.to_wkt(shapely.union(cert.region, shapely.Point(target)
                                                                             .buffer(0.002)))}}
    cert.extra = bad
    assert check_certificate(cert, rules, space)
    # an independent search that changes faces only where brute force finds a way round the puck
    closest, refused, exhausted = switch_lattice_search(setting, start, target)
    assert exhausted and refused > 0
    assert closest > 0.003, f"the search came {closest * 1e3:.2f} mm from the target of a certified task"


def test_a_feasible_task_with_switches_is_not_certified() -> None:
    """``exec60-00001`` (slope, one obstacle) is solved with a switch from ``inclined`` to ``left``: its
    faces' sets must reach the target."""
    task = generated("execution_60.yaml", "exec60-00001")
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    cert, why = certify_switches(setting_rules(setting), placement_space(setting), np.array(task.start),
                                 np.array(task.target))
    assert cert is None and "came within the gap of the target" in why
