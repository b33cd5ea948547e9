"""The backward-reachable set with exact pieces (``certificate.LAST_BACKWARD``: 2.5 mm cells, pieces stored
exactly, a 0.05 mm start gap; not tried by the verdict, see its comment). On a task at the edge of the
rules the growth of the stored pieces alone takes the default sets to the start."""

from __future__ import annotations

import numpy as np
from test_verdicts import _rules_of, depth_inside, generated, lattice_search

from tooltransfer.planner.planning.verdicts.certificate import LAST_BACKWARD, certify, check_certificate


def test_a_task_whose_grown_pieces_reach_the_start_is_certified_with_exact_pieces() -> None:
    """``exec60-00015``: the default grids' sets (pieces grown by 20 um at each update) come within the gap
    of the start; the set with its pieces exact leaves it out, the check replays it, and the test suite's
    lattice search neither comes near the target nor enters the set."""
    task = generated("execution_60.yaml", "exec60-00015")
    setting, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    cert, why = certify(rules, start, target)
    assert cert is None and "came within the gap of the start" in why
    side, gap, blocks = LAST_BACKWARD
    cert, why = certify(rules, start, target, h=(side,), max_blocks=blocks, gap=gap, exact=True)
    assert cert is not None and cert.kind == "backward_reachable", why
    assert cert.extra["start_gap"] == gap and cert.to_dict()["start_gap"] == gap
    assert check_certificate(cert, rules) == []
    cert.extra = cert.extra | {"start_gap": 1e-9}  # a gap below the rounding proves nothing: refused
    assert "start gap" in check_certificate(cert, rules)[0]
    visited: list = []
    closest = lattice_search(setting, start, target, ends_held=True, visited=visited)
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"
    assert len(visited) > 100 and depth_inside(cert.region, np.asarray(visited)) < 5e-4
