"""The order of the candidates of a tool choice: executed success first, then margins, then duration.

A candidate's key, compared largest first (:func:`rank_key`):

1. its verdict: a ``solved`` plan before an ``unknown`` task before a certified ``infeasible`` one;
2. its executions (:class:`Executions`), as three passes in this order of weight: the closed loop on
   the nominal platform ends within :data:`CLOSED_LOOP_TOL` of the target, the closed loop on the
   mismatched plant within :data:`MISMATCH_TOL`, the open loop within :data:`OPEN_LOOP_TOL`. A plan
   not executed (:func:`needs_execution` said a better one had already passed every execution) counts
   as passing none;
3. its weakest margin (:func:`margin_score`): the friction cone's [rad], the contact's distance from a
   face's edge [m] and the clearance to obstacles [m] (object and tool), each divided by its scale
   (:data:`MARGIN_SCALES`) and capped at 1, the smallest of the three, rounded to
   :data:`SCORE_STEP` (differences below it are noise of the optimiser, not of the tool);
4. the shorter plan duration [s].

Executing the plans in the order of 3-4 (:func:`plan_order`) and stopping at the first that passes
every execution gives the same best candidate as executing them all: every candidate before it
failed an execution, every one after it has no larger margin key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

#: Final error [m] within which each execution passes.
CLOSED_LOOP_TOL = 0.002
MISMATCH_TOL = 0.003
OPEN_LOOP_TOL = 0.005
#: The executions of a solved plan, in their order of weight (names as in :class:`Executions`).
EXECUTIONS = ("closed_loop", "mismatch_closed_loop", "open_loop")
TOLERANCES = {"closed_loop": CLOSED_LOOP_TOL, "mismatch_closed_loop": MISMATCH_TOL, "open_loop": OPEN_LOOP_TOL}
#: Scale of each margin [rad, m, m]: a margin at least this large counts fully (the friction cone's
#: half-angle is atan(mu) ~ 0.67 rad at mu 0.8; 2 mm keeps a contact off an edge against the camera's
#: noise; 5 mm is the default safety margin).
MARGIN_SCALES = {"friction_cone": 0.2, "contact_edge": 0.002, "clearance": 0.005}
SCORE_STEP = 0.02
VERDICT_ORDER = {"solved": 2, "unknown": 1, "infeasible": 0}


@dataclass(frozen=True)
class Executions:
    """Final errors [m] of a solved plan's executions (None: not run, or it raised; ``status`` says which).

    Attributes:
        open_loop: the planned joints tracked on the nominal MuJoCo platform.
        closed_loop: re-planning from the observed object on the nominal platform.
        mismatch_closed_loop: the closed loop on the mismatched plant (MuJoCo, other frictions).
        status: per execution, ``"done"``, the closed loop's own status, or ``"exception: ..."``.
    """

    open_loop: float | None = None
    closed_loop: float | None = None
    mismatch_closed_loop: float | None = None
    status: Mapping[str, str] | None = None

    def passes(self) -> tuple[bool, bool, bool]:
        """Whether each execution of :data:`EXECUTIONS` ended within its tolerance."""
        return tuple(_within(getattr(self, k), TOLERANCES[k]) for k in EXECUTIONS)  # type: ignore[return-value]

    def passed_all(self) -> bool:
        return all(self.passes())


def _within(error: float | None, tol: float) -> bool:
    return error is not None and math.isfinite(error) and error <= tol


def execution_passed(mode: str, error: float | None) -> bool:
    """Whether an execution of ``mode`` (:data:`EXECUTIONS`) that ended ``error`` [m] from the target passed."""
    return _within(error, TOLERANCES[mode])


def margins(metrics: Mapping[str, Any]) -> dict[str, float]:
    """The plan's three margins from its metrics: ``friction_cone`` [rad], ``contact_edge`` [m] and
    ``clearance`` [m] (the smaller of the object's and the tool's clearance to obstacles; infinite
    without obstacles). A missing or non-finite metric (but an infinite clearance) counts as 0."""

    def value(key: str) -> float:
        v = metrics.get(key)
        try:
            f = float(v)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            return 0.0
        return f if not math.isnan(f) else 0.0

    clear = min(value("obstacle_clearance_min") if "obstacle_clearance_min" in metrics else math.inf,
                value("tool_obstacle_clearance_min") if "tool_obstacle_clearance_min" in metrics else math.inf)
    return {"friction_cone": value("friction_cone_margin_min"), "contact_edge": value("contact_edge_margin_min"),
            "clearance": clear}


def margin_score(metrics: Mapping[str, Any]) -> float:
    """The weakest of the plan's margins, each relative to its scale and capped at 1, rounded to
    :data:`SCORE_STEP` (in [0, 1]; negative margins count as 0)."""
    m = margins(metrics)
    score = min(min(1.0, max(0.0, m[k] / MARGIN_SCALES[k])) for k in MARGIN_SCALES)
    return round(round(score / SCORE_STEP) * SCORE_STEP, 6)


def weakest_margin(metrics: Mapping[str, Any]) -> str:
    """Which margin is the weakest, relative to its scale (for the reason shown beside a candidate)."""
    m = margins(metrics)
    return min(MARGIN_SCALES, key=lambda k: m[k] / MARGIN_SCALES[k])


def _duration(metrics: Mapping[str, Any]) -> float:
    try:
        d = float(metrics.get("duration", math.inf))
    except (TypeError, ValueError):
        return math.inf
    return d if math.isfinite(d) else math.inf


def plan_key(verdict: str, metrics: Mapping[str, Any]) -> tuple[float, ...]:
    """The key of a candidate before any execution: its verdict, then (solved plans) its margin
    score and shorter duration; larger is better."""
    if verdict != "solved":
        return (VERDICT_ORDER.get(verdict, 0),)
    return (VERDICT_ORDER["solved"], margin_score(metrics), -_duration(metrics))


def rank_key(verdict: str, metrics: Mapping[str, Any], executions: Executions | None) -> tuple[float, ...]:
    """The whole key of a candidate (module docstring); larger is better."""
    key = plan_key(verdict, metrics)
    if verdict != "solved":
        return key
    passes = executions.passes() if executions is not None else (False, False, False)
    return (key[0], *(float(p) for p in passes), *key[1:])


def plan_order(candidates: Sequence[tuple[str, Mapping[str, Any]]]) -> list[int]:
    """Indices of the ``(verdict, metrics)`` candidates by :func:`plan_key`, best first (stable: the
    given order breaks ties)."""
    return sorted(range(len(candidates)), key=lambda i: plan_key(*candidates[i]), reverse=True)


def needs_execution(order: Sequence[int], executed: Mapping[int, Executions]) -> list[int]:
    """The solved candidates (``order``: indices by :func:`plan_order`, solved ones only) still to
    execute: those not yet executed ahead of the first that passed every execution (none once every
    candidate ahead of it was executed and failed one: the module docstring says why it is then the
    best; one behind it can never rank above it), all of those not yet executed while none has passed."""
    for n, i in enumerate(order):
        ex = executed.get(i)
        if ex is not None and ex.passed_all():
            return [j for j in order[:n] if j not in executed]
    return [j for j in order if j not in executed]


def known_best(order: Sequence[int], executed: Mapping[int, Executions]) -> int | None:
    """The candidate of ``order`` (as for :func:`needs_execution`) known to be the best of those
    planned: the first that passed every execution with every one ahead of it executed (and failed
    one); None while there is none."""
    for i in order:
        ex = executed.get(i)
        if ex is None:
            return None
        if ex.passed_all():
            return i
    return None
