"""``choose_tool``: plan a task with every candidate tool in parallel, execute the solved plans, rank them.

The work runs on ``workers`` cores (default 2, at most the machine's; BLAS on one thread each, as the
command line sets it), as :mod:`.schedule` says: a process per candidate (up to
:data:`.schedule.PROCESSES_PER_WORKER` per core) plans it, so every candidate plans from the start
and a slow one holds back neither the others nor the best plan's executions; the solved plans are
executed (:mod:`.executions`) once a core is free of the candidates on their quick first stage or a
grace period after the first solved plan, in the order of their plans' margins and duration
(:func:`.ranking.plan_order`), until one plan passes every execution (the best is then known,
:mod:`.ranking`; ``execute_all`` executes every solved plan). Once a plan has passed every
execution, the candidates in their slower stages are stopped, their verdict ``unknown``
(:mod:`.schedule`'s deadline; ``wait_all`` waits for every verdict). The processes are forked from this one where the
platform allows, after the task's skills are learned (or read from the cache) and the jobs' modules
imported here, so no process learns, loads or imports them again.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.choose import schedule
from tooltransfer.planner.apps.choose.candidates import Candidate, candidates
from tooltransfer.planner.apps.choose.executions import Executed, Planned
from tooltransfer.planner.apps.choose.ranking import Executions, rank_key
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.problems.task import Task


@dataclass(frozen=True)
class Ranked:
    """One candidate tool in the ranking.

    Attributes:
        rank: 1 for the best.
        label: the tool as the user named it; tool: its own name.
        verdict: ``solved``, ``infeasible`` or ``unknown`` (as ``solve`` gives it).
        reason: the planner's reason (for a solved plan: "").
        plan: the plan (None when planning raised).
        executions: the final errors of the executions run (None: not executed).
        runs: every execution run, by mode (:data:`.executions.MODES`).
        planning_wall, planning_cpu: [s] (a candidate stopped: the wall time until it was stopped, CPU 0:
            its CPU time counts in the choice's only).
        stopped: whether its planning was stopped at the deadline (:mod:`.schedule`; verdict ``unknown``).
    """

    rank: int
    label: str
    tool: str
    verdict: str
    reason: str
    plan: Plan | None
    executions: Executions | None
    runs: dict[str, Executed] = field(default_factory=dict)
    planning_wall: float = 0.0
    planning_cpu: float = 0.0
    stopped: bool = False


@dataclass(frozen=True)
class Choice:
    """The outcome of :func:`choose_tool`: the ranking (best first), the wall time and the CPU time [s]
    of the whole choice (this process and every job of the pool)."""

    task: Task
    ranking: list[Ranked]
    wall: float
    cpu: float

    @property
    def best(self) -> Ranked | None:
        """The best candidate, or None when no tool solved the task."""
        return self.ranking[0] if self.ranking and self.ranking[0].verdict == "solved" else None

    @property
    def plan(self) -> Plan | None:
        """The best candidate's plan (None when no tool solved the task)."""
        return self.best.plan if self.best is not None else None

    @property
    def verdict(self) -> str:
        """``solved`` when some tool solved the task, else ``unknown`` when some tool left it undecided,
        else ``infeasible`` (every tool has a certificate)."""
        verdicts = {r.verdict for r in self.ranking}
        return "solved" if "solved" in verdicts else "unknown" if "unknown" in verdicts else "infeasible"


def choose_tool(task: Task | str | Path, tools: Sequence[str | Path] | None = None, *, workers: int = 2,
                execute_all: bool = False, wait_all: bool = False, seed: int = 0, budget: float = 1.0,
                executor: Executor | None = None, progress: Callable[[str], None] | None = None) -> Choice:
    """Choose the best tool for ``task`` among ``tools`` (module docstring).

    Args:
        task: a :class:`~tooltransfer.problems.task.Task`, a task file or a bundled task's name; its own
            tool is not a candidate unless listed.
        tools: library tool names and tool-file paths (None: every library tool).
        workers: the cores the choice uses (1: all in this process); at most the machine's. The pool this
            call makes has a process per candidate, at most :data:`.schedule.PROCESSES_PER_WORKER` per
            worker (the cores shared among them); a given ``executor`` runs ``workers`` jobs at a time.
        execute_all: execute every solved plan, not only until the best is known.
        wait_all: wait for every candidate's verdict; default: once a plan passed every execution, the
            candidates in their slower stages are stopped (:mod:`.schedule`) and ranked ``unknown``
            with the reason "stopped after <tool> passed every execution; ..." (only in the pool this
            call makes: with ``workers=1`` or an ``executor`` every verdict is waited for).
        seed: the closed loops' camera-noise seed.
        budget: the planner's search and certificate budgets multiplied (``solve(budget=)``).
        executor: a pool to use (kept open) instead of one made for this call.
        progress: called with a line of text as the work goes.

    Returns:
        The :class:`Choice`; its ``cpu`` counts this process and, for the pool this call makes, its
        processes' whole CPU time (jobs stopped or cut short included), else the jobs' own.

    Raises:
        InputError: naming ``tools``: an unknown tool name, a missing or invalid tool file.
    """
    wall0, cpu0 = time.perf_counter(), time.process_time()
    if isinstance(task, str | Path):
        from tooltransfer.problems.task import load_task

        task = load_task(task)
    from tooltransfer.planner.planning.solve import check_budget

    check_budget(budget)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError("workers", "a whole number >= 1", workers)
    cands = candidates(task, tools, field="tools")
    say = progress or (lambda text: None)
    workers = min(workers, os.cpu_count() or 1, max(1, len(cands)))
    own = executor is None and workers > 1
    children0 = schedule.children_cpu()
    pools: schedule.Pools | None = None
    if own:
        schedule.warm(task)
        pools = schedule.Pools.make(workers, len(cands))
    elif executor is not None:
        pools = schedule.Pools.given(executor, workers)
    options = schedule.Options(budget=budget, seed=seed, execute_all=execute_all, wait_all=wait_all)
    try:
        say(f"planning with {len(cands)} tools")
        w = schedule.work(cands, pools, options, say)
    finally:
        if pools is not None:
            pools.stop()
    jobs = w.cpu
    children1 = schedule.children_cpu()
    if own and children0 is not None and children1 is not None:  # the pool's processes, waited for
        jobs = max(jobs, children1 - children0)
    ranking = _rank(cands, [w.planned[i] for i in range(len(cands))], w.runs, w.executed, set(w.stopped))
    return Choice(task, ranking, time.perf_counter() - wall0, time.process_time() - cpu0 + jobs)


def _rank(cands: Sequence[Candidate], planned: Sequence[Planned], runs: dict[int, dict[str, Executed]],
          executed: dict[int, Executions], stopped: set[int]) -> list[Ranked]:
    """The candidates best first (:func:`.ranking.rank_key`); ``executed``: the plans every execution of
    which ran, ``runs``: every execution run (a plan whose executions were cut short keeps none);
    ``stopped``: the candidates stopped at the deadline."""
    def key(i: int) -> tuple[Any, ...]:
        p = planned[i]
        ex = executed.get(i)
        metrics = p.plan.metrics if p.plan is not None else {}
        # executed plans before those not executed at equal keys (a plan not executed passed nothing yet)
        return (*rank_key(p.verdict, metrics, ex), ex is not None)

    order = sorted(range(len(cands)), key=key, reverse=True)
    return [Ranked(rank=n + 1, label=cands[i].label, tool=cands[i].tool, verdict=planned[i].verdict,
                   reason=planned[i].reason if planned[i].verdict != "solved" else "", plan=planned[i].plan,
                   executions=executed.get(i), runs=dict(runs.get(i, {})) if i in executed else {},
                   planning_wall=planned[i].wall,
                   planning_cpu=planned[i].cpu, stopped=i in stopped) for n, i in enumerate(order)]
