"""The verdict of a task the planner did not solve: ``infeasible`` with a certificate, else ``unknown``.

The planner's search is bounded (a few scored push sequences, at most ``oe.max_pushes`` pushes), so
its failure says nothing about the task. :func:`attach_verdict` looks for a certificate under the
rules of :mod:`~tooltransfer.planner.planning.verdicts.rules` (:func:`certify`; once the search has failed, also
:func:`~.certificate.certify_exact_backward`, the backward set with exact pieces, then
:func:`certify_switches`, the switches the tool cannot make, then :func:`~.certificate.certify_both_ways`, the
sets both ways on log-polar cells) and returns the plan
with ``status`` ``"infeasible"`` and the certificate as its evidence when one is found, else with
``status`` ``"unknown"`` (or ``"violated"`` for a plan that broke its hard checks) and evidence that
says what was searched and why nothing was proved (and ``budget_limited``: whether a larger ``budget``
could change that, :func:`budget_limited`; ``holds``: where on each face the contact holds the puck at the start
and at the target, :func:`~.holds_at.face_holds`, the reason naming a hold narrower than the search's windows).
"""

from __future__ import annotations

import copy
import hashlib
import json
import time
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np

from tooltransfer.planner.planning.plan import Plan
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.verdicts.backward import BUDGET_SPENT
from tooltransfer.planner.planning.verdicts.certificate import (
    FINE_BLOCKS,
    Certificate,
    certify,
    certify_both_ways,
    certify_exact_backward,
    certify_switches,
)
from tooltransfer.planner.planning.verdicts.holds_at import face_holds, narrow_hold
from tooltransfer.planner.planning.verdicts.rules import PushRules, setting_rules
from tooltransfer.planner.planning.verdicts.switch_space import placement_space

#: Block updates the backward-reachable set may make before the verdict is left ``unknown``.
CERTIFY_BLOCKS = 20000


def budget_limited(metrics: dict[str, float], not_proved: str) -> bool:
    """Whether an ``unknown`` verdict's search or certificate stopped on its budget: an attempt of the
    guided search ran out of expansions (``guided_attempts_on_budget``) or a certificate's set out of block
    updates or of vertices grown (``not_proved``). Where neither did, every attempt searched its whole space
    under its own rules and every grid's set reached the start: a larger ``budget`` is unlikely to decide
    the task (benchmarks/README.md: on the verdict benchmark, 4 times the budget decided 6 of 32 unknowns,
    16 times none more, before the exact backward set was tried; it decides 2 of the 16 left with it, both by
    a plan), a wider search or a tighter certificate might."""
    return metrics.get("guided_attempts_on_budget", 0.0) > 0.0 or BUDGET_SPENT in not_proved


@dataclass(frozen=True)
class Sought:
    """A look for a certificate (:func:`seek_certificate`): the certificate, or None with ``why`` nothing
    was proved, the seconds [s] it took, and whether it was taken from an earlier look at the same task in this
    process (:func:`remembered`; ``spent`` is then the time the look took here, ``shared`` the first one's [s])."""

    cert: Certificate | None
    why: str
    spent: float
    reused: bool = False
    shared: float = 0.0


#: The looks for certificates made in this process, newest last, by :func:`task_key` (at most :data:`REMEMBERED`).
_LOOKS: OrderedDict[str, Sought] = OrderedDict()
#: How many looks :data:`_LOOKS` keeps.
REMEMBERED = 32


def task_key(setting: Setting, start: np.ndarray, target: np.ndarray, *parts: Any) -> str:
    """A digest of what a certificate depends on: the world (``setting``: its description, mechanics and
    margin, what makes two settings equal), ``start`` and ``target`` (2,) [m] and ``parts`` (budgets, the
    attempt). Not the variant: a certificate is a property of the task, so the variants of a task
    (``compare``; a batch's rows where one slot runs them in turn) share each look."""
    data = json.dumps([setting.describe(), repr(setting.mechanics), setting.margin,
                       np.asarray(start, dtype=np.float64).tolist(), np.asarray(target, dtype=np.float64).tolist(),
                       list(parts)], sort_keys=True, default=str)
    return hashlib.sha256(data.encode()).hexdigest()


def remembered(key: str, look: Callable[[], Sought]) -> Sought:
    """The look of ``key`` made earlier in this process (``reused``, with the time of this call), else ``look()``
    made and kept. Sound to share: every look is deterministic in what :func:`task_key` digests."""
    t0 = time.perf_counter()
    if key in _LOOKS:
        _LOOKS.move_to_end(key)
        first = _LOOKS[key]  # a copy of its certificate: a plan's is its own
        return replace(first, cert=copy.deepcopy(first.cert), spent=time.perf_counter() - t0, reused=True,
                       shared=first.spent)
    found = look()
    _LOOKS[key] = found
    while len(_LOOKS) > REMEMBERED:
        _LOOKS.popitem(last=False)
    return found


def seek_certificate(setting: Setting, start: np.ndarray, target: np.ndarray, *, max_blocks: int = CERTIFY_BLOCKS,
                     budget: float = 1.0) -> Sought:
    """A certificate that the object cannot be pushed from ``start`` to ``target`` (2,) [m] under the rules
    of ``setting`` (:func:`certify`); ``budget`` scales its block updates (``max_blocks`` and each of
    :data:`FINE_BLOCKS`). Made once per task in a process (:func:`remembered`)."""
    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)

    def look() -> Sought:
        t0 = time.perf_counter()
        cert, why = certify(setting_rules(setting), start, target, max_blocks=round(max_blocks * budget),
                            fine_blocks=tuple(round(b * budget) for b in FINE_BLOCKS))
        return Sought(cert, why, time.perf_counter() - t0)

    return remembered(task_key(setting, start, target, "first", max_blocks, budget), look)


def attach_verdict(plan: Plan, setting: Setting, start: np.ndarray, target: np.ndarray, *,
                   max_blocks: int = CERTIFY_BLOCKS, budget: float = 1.0, sought: Sought | None = None) -> Plan:
    """``plan`` (not ``solved``) with its verdict and evidence (module docstring); a solved plan is
    returned as it is, with the evidence that it is one. ``sought``: the certificate already looked for
    (:func:`seek_certificate`, before the search's costlier stages: a task it proves infeasible needs no
    more search); else it is looked for here, ``budget`` scaling its block updates."""
    if plan.status == "solved":
        return replace(plan, evidence={"verdict": "solved", "kind": "plan",
                                       "checks": "every hard check holds (metrics)", "budget": budget})
    if sought is None:
        sought = seek_certificate(setting, start, target, max_blocks=max_blocks, budget=budget)
    if sought.cert is None and plan.status != "violated":
        sought = _after_search(sought, setting, start, target, budget)
    cert, why, spent = sought.cert, sought.why, sought.spent
    metrics = {**plan.metrics, "time_certify": spent}
    if "time_total" in metrics:
        metrics["time_total"] += spent
    searched = plan.reason or "no plan"
    reused = {"certificate_reused": True, "time_certify_shared": sought.shared} if sought.reused else {}
    if cert is not None:
        evidence: dict[str, Any] = {"verdict": "infeasible", "kind": cert.kind, "searched": searched,
                                    "certificate": cert.to_dict(), "budget": budget, **reused}
        return replace(plan, status="infeasible", metrics=metrics, evidence=evidence,
                       reason=f"certified infeasible ({cert.kind}): {cert.reason}; the planner's search: {searched}")
    status: Literal["unknown", "violated"] = "violated" if plan.status == "violated" else "unknown"
    evidence = {"verdict": "unknown", "kind": "search_exhausted" if status == "unknown" else "violated",
                "searched": searched, "not_proved": why, "budget": budget}
    if status == "violated":
        evidence.update(reused)
        return replace(plan, status=status, metrics=metrics, evidence=evidence)
    evidence["budget_limited"] = budget_limited(plan.metrics, why)
    holds = {where: face_holds(setting, at) for where, at in (("start", start), ("target", target))}
    evidence["holds"] = {where: [h.to_dict() for h in per] for where, per in holds.items()}
    evidence.update(reused)
    narrow = "; ".join(c for c in (narrow_hold(holds["start"], "the start"), narrow_hold(holds["target"], "the target"))
                       if c)
    return replace(plan, status=status, metrics=metrics, evidence=evidence,
                   reason=f"{searched} (not proved infeasible: {why}{'; ' + narrow if narrow else ''})")


def _after_search(sought: Sought, setting: Setting, start: np.ndarray, target: np.ndarray, budget: float) -> Sought:
    """``sought`` (no certificate found), or the first certificate of the attempts made only once the search
    has failed, in turn: the backward set with exact pieces (:func:`~.certificate.certify_exact_backward`), then
    the ``switch_separated`` sets (:func:`certify_switches`: the faces' sets from the start, passed from face to
    face only where the tool can get round the puck), then the ``forward_backward`` sets on log-polar cells
    (:func:`~.certificate.certify_both_ways`); ``budget`` scales their block updates (and vertices).
    Each costs some seconds where it proves something and where it does not; made once per task in a process
    (:func:`remembered`)."""

    def look() -> Sought:
        t0, whys = time.perf_counter(), []
        for attempt in later_attempts(setting_rules(setting), setting, start, target, budget):
            cert, why = attempt()
            if cert is not None:
                return Sought(cert, "", time.perf_counter() - t0)
            whys.append(why)
        return Sought(None, "; ".join(whys), time.perf_counter() - t0)

    later = remembered(task_key(setting, start, target, "after search", budget), look)
    found = later.cert is not None  # then the certificate is the later look's alone
    return Sought(later.cert, "" if found else f"{sought.why}; {later.why}", sought.spent + later.spent,
                  later.reused if found else sought.reused or later.reused, sought.shared + later.shared)


def later_attempts(rules: PushRules, setting: Setting, start: np.ndarray, target: np.ndarray, budget: float = 1.0
                   ) -> tuple[Callable[[], tuple[Certificate | None, str]], ...]:
    """The certificates tried only once the search has failed, in the verdict's order, each a call giving
    ``(certificate or None, why not)`` under ``rules`` (the tool's placements of ``setting``): the backward set
    with exact pieces, then the ``switch_separated`` sets, then the ``forward_backward`` sets on log-polar cells;
    ``budget`` scales their block updates (and vertices)."""
    return (lambda: certify_exact_backward(rules, start, target, budget=budget),
            lambda: certify_switches(rules, placement_space(setting), start, target, budget=budget),
            lambda: certify_both_ways(rules, start, target, budget=budget))
