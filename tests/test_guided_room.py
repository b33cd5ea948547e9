"""Which guided plan :func:`tooltransfer.planner.planning.solve._guided` keeps when a plan passes within
``GUIDED_ROOM`` of an obstacle: a later attempt's roomier plan replaces it, but not one at the widest
share of the friction cone after a plan at a narrower share (it would spend the margin the share keeps
for an error in ``mu``). The attempts are stand-ins: what is tested is the choice, not the search."""

from __future__ import annotations

from collections.abc import Generator
from types import SimpleNamespace
from typing import Any

import pytest

from tooltransfer.planner.planning import solve as solve_module

TIGHT, ROOMY = 0.0005, 0.003  # the tool's least clearance [m] of a plan


def _attempt(k: int, room: float, widest: bool) -> SimpleNamespace:
    metrics = {"k": float(k), "room": room, **({"guided_widest": 1.0} if widest else {})}
    return SimpleNamespace(status="solved", metrics=metrics, reason="")


def _ladder(attempts: list[SimpleNamespace], tried: list[int]) -> Generator[Any, Any, None]:
    for k, a in enumerate(attempts):
        tried.append(k)
        yield a


def _complete(task, setting, guided, switch, recontact, stages, base, switches) -> SimpleNamespace:
    """The stand-in whole plan: solved, its clearances the attempt's room."""
    room = guided.metrics["room"]
    return SimpleNamespace(status="solved", reason="", metrics={
        **guided.metrics, "tool_obstacle_clearance_min": room, "switch_obstacle_clearance_min": room})


@pytest.mark.parametrize(("attempts", "kept", "tried"), [
    ([(TIGHT, False), (ROOMY, False)], 1, [0, 1]),  # a roomier plan at the same share replaces it
    ([(TIGHT, False), (ROOMY, True), (ROOMY, True)], 0, [0, 1]),  # none at the widest after a narrower
    ([(TIGHT, True), (ROOMY, True)], 1, [0, 1]),  # at the widest after one at the widest: it does
    ([(TIGHT, False), (TIGHT, False)], 0, [0, 1]),  # none roomier: the first tight plan
])
def test_a_plan_with_little_room_is_replaced_only_at_its_share_or_a_narrower(monkeypatch, attempts, kept,
                                                                             tried) -> None:
    monkeypatch.setattr(solve_module, "_complete", _complete)
    made = [_attempt(k, room, widest) for k, (room, widest) in enumerate(attempts)]
    seen: list[int] = []
    failed = SimpleNamespace(metrics={}, reason="")
    plan = solve_module._guided(None, None, _ladder(made, seen), failed, None, None, {}, 0.0)
    assert plan.metrics["k"] == kept
    assert seen == tried


def test_the_plan_kept_with_little_room_is_sent_back_to_the_ladder(monkeypatch) -> None:
    """After a solved plan with little room, ``_guided`` sends that plan back to the ladder (which then
    skips its last attempt, tests/test_guided_field.py); after a roomy one it stops; after an attempt
    that failed it sends nothing."""
    monkeypatch.setattr(solve_module, "_complete", _complete)
    sent: list[Any] = []

    def ladder(attempts: list[SimpleNamespace]) -> Generator[Any, Any, None]:
        for a in attempts:
            sent.append((yield a))

    failed_attempt = SimpleNamespace(status="infeasible", metrics={}, reason="no path")
    made = [failed_attempt, _attempt(1, TIGHT, False), _attempt(2, TIGHT, False)]
    failed = SimpleNamespace(metrics={}, reason="")
    plan = solve_module._guided(None, None, ladder(made), failed, None, None, {}, 0.0)
    assert plan.metrics["k"] == 1
    assert sent[0] is None and sent[1] is plan and sent[2] is plan
    sent.clear()
    plan = solve_module._guided(None, None, ladder([_attempt(0, ROOMY, False), _attempt(1, ROOMY, False)]), failed,
                                None, None, {}, 0.0)
    assert plan.metrics["k"] == 0 and sent == []
