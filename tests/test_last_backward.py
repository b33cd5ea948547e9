"""The backward-reachable set with exact pieces (``certificate.LAST_BACKWARD``: 2.5 mm cells, pieces stored
exactly, a 0.05 mm start gap, bounded block updates and vertices grown; the verdict's last backward attempt).
On a task at the edge of the rules the growth of the stored pieces alone takes the default sets to the start."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from test_verdicts import _rules_of, depth_inside, generated, lattice_search

from tooltransfer.planner.planning.solve import solve
from tooltransfer.planner.planning.verdicts.backward import BUDGET_SPENT
from tooltransfer.planner.planning.verdicts.certificate import (
    LAST_BACKWARD,
    certify,
    certify_exact_backward,
    check_certificate,
)
from tooltransfer.planner.planning.verdicts.decide import budget_limited


def test_a_task_whose_grown_pieces_reach_the_start_is_certified_with_exact_pieces() -> None:
    """``exec60-00015``: the default grids' sets (pieces grown by 20 um at each update) come within the gap
    of the start; the set with its pieces exact leaves it out, the check replays it, and the test suite's
    lattice search neither comes near the target nor enters the set."""
    task = generated("execution_60.yaml", "exec60-00015")
    setting, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    cert, why = certify(rules, start, target)
    assert cert is None and "came within the gap of the start" in why
    cert, why = certify_exact_backward(rules, start, target)  # as the verdict tries it
    assert cert is not None and cert.kind == "backward_reachable", why
    gap = LAST_BACKWARD.gap
    assert cert.extra["start_gap"] == gap and cert.to_dict()["start_gap"] == gap
    assert check_certificate(cert, rules) == []
    cert.extra = cert.extra | {"start_gap": 1e-9}  # a gap below the rounding proves nothing: refused
    assert "start gap" in check_certificate(cert, rules)[0]
    visited: list = []
    closest = lattice_search(setting, start, target, ends_held=True, visited=visited)
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"
    assert len(visited) > 100 and depth_inside(cert.region, np.asarray(visited)) < 5e-4


def test_the_vertices_grown_bound_the_exact_set_and_say_a_budget_stopped_it() -> None:
    """The same set with a bound of 20,000 vertices grown (about 6 % of what it takes): no certificate, and
    the reason says a budget stopped it, so the verdict is ``budget_limited`` (a larger ``--budget`` may help)."""
    task = generated("execution_60.yaml", "exec60-00015")
    _, rules = _rules_of(task)
    cert, why = certify_exact_backward(rules, np.array(task.start), np.array(task.target),
                                       last=replace(LAST_BACKWARD, vertices=20_000))
    assert cert is None and f"{BUDGET_SPENT} 20000 vertices grown" in why
    assert budget_limited({}, why)


def test_the_verdict_tries_it_once_the_search_has_failed() -> None:
    """``solve`` on ``exec60-00015``: the search finds no plan, the default sets reach the start, and the
    verdict is ``infeasible`` with the exact set's certificate (its start gap stored with it)."""
    plan = solve(generated("execution_60.yaml", "exec60-00015"))
    assert plan.status == "infeasible", plan.reason
    assert plan.evidence["kind"] == "backward_reachable"
    assert plan.evidence["certificate"]["start_gap"] == LAST_BACKWARD.gap
