"""``choose_tool``: plan a task with every candidate tool in parallel, execute the solved plans, rank them.

The work runs in a process pool of ``workers`` processes (default 2, at most the machine's cores;
BLAS on one thread each, as the command line sets it): every candidate is planned, and the solved
plans are executed (:mod:`.executions`) in the order of their plans' margins and duration
(:func:`.ranking.plan_order`), one execution per pool slot at a time, until one plan passes every
execution (the best is then known, :mod:`.ranking`; ``execute_all`` executes every solved plan).
Plans go first; executions fill the slots the plans leave free, so a plan solved early is executed
while the slow candidates (those left without a plan, whose certificate searches take longest) are
still planned.
The pool's processes are forked from this one where the platform allows, after the task's skills
are learned (or read from the cache) here, so no process learns or loads them again.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED as _FIRST
from concurrent.futures import Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.choose.candidates import Candidate, candidates
from tooltransfer.planner.apps.choose.executions import MODES, Executed, Planned, execute, plan_candidate
from tooltransfer.planner.apps.choose.ranking import Executions, needs_execution, plan_order, rank_key
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.problems.task import Task

#: The order in which one plan's executions are handed out (the longest first: two slots finish together).
_SUBMIT_ORDER = ("closed_loop", "mismatch_closed_loop", "open_loop")


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
        planning_wall, planning_cpu: [s].
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


def _pool(workers: int) -> ProcessPoolExecutor:
    import multiprocessing

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    return ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method))


def _stop(pool: ProcessPoolExecutor) -> None:
    """End a pool this choice made now: jobs queued are dropped, running ones (executions no longer
    needed) are ended with their processes."""
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        if proc.is_alive():
            proc.terminate()


def _warm(task: Task) -> None:
    """Learn (or read from the cache) the task's skills here, before the pool's processes fork."""
    from tooltransfer.planner.planning.setting import task_skills
    from tooltransfer.planner.planning.variant_registry import needs_ss_skill

    task_skills(task, need_ss=needs_ss_skill(task.variants.ss))


def choose_tool(task: Task | str | Path, tools: Sequence[str | Path] | None = None, *, workers: int = 2,
                execute_all: bool = False, seed: int = 0, budget: float = 1.0, executor: Executor | None = None,
                progress: Callable[[str], None] | None = None) -> Choice:
    """Choose the best tool for ``task`` among ``tools`` (module docstring).

    Args:
        task: a :class:`~tooltransfer.problems.task.Task`, a task file or a bundled task's name; its own
            tool is not a candidate unless listed.
        tools: library tool names and tool-file paths (None: every library tool).
        workers: processes planning and executing (1: all in this process); at most the machine's cores.
        execute_all: execute every solved plan, not only until the best is known.
        seed: the closed loops' camera-noise seed.
        budget: the planner's search and certificate budgets multiplied (``solve(budget=)``).
        executor: a pool to use (kept open) instead of one made for this call.
        progress: called with a line of text as the work goes.

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
    pool: Executor | None = executor
    own = executor is None and workers > 1
    if own:
        _warm(task)
        pool = _pool(workers)
    try:
        say(f"planning with {len(cands)} tools")
        w = _work(cands, pool, workers, budget, execute_all, seed, say)
    finally:
        if own and isinstance(pool, ProcessPoolExecutor):
            _stop(pool)
    ranking = _rank(cands, [w.planned[i] for i in range(len(cands))], w.runs, w.executed)
    return Choice(task, ranking, time.perf_counter() - wall0, time.process_time() - cpu0 + w.cpu)


class _Work:
    """The state of one choice's work: the plans and executions done, and what to run next."""

    def __init__(self, n: int, execute_all: bool) -> None:
        self.n = n
        self.execute_all = execute_all
        self.planned: dict[int, Planned] = {}
        self.runs: dict[int, dict[str, Executed]] = {}
        self.executed: dict[int, Executions] = {}
        self.cpu = 0.0  # of the jobs [s]

    def order(self) -> list[int]:
        """The solved candidates planned so far, by their plans' margins and duration (best first)."""
        solved = [i for i in sorted(self.planned) if self.planned[i].verdict == "solved"
                  and self.planned[i].plan is not None]
        return [solved[k] for k in plan_order([("solved", self.plan(i).metrics) for i in solved])]

    def plan(self, i: int) -> Plan:
        plan = self.planned[i].plan
        assert plan is not None  # only solved candidates with a plan are executed
        return plan

    def wanted(self) -> list[tuple[int, str]]:
        """The executions still to run, best candidate first: until the best is known once every
        candidate is planned (:func:`.ranking.needs_execution`); before, every solved plan's (in the
        pool's free slots: the best so far may be the best)."""
        order = self.order()
        if len(self.planned) < self.n or self.execute_all:
            want = [i for i in order if i not in self.executed]
        else:
            want = needs_execution(order, self.executed)
        return [(i, m) for i in want for m in _SUBMIT_ORDER if m not in self.runs.get(i, {})]

    def done(self) -> bool:
        return len(self.planned) == self.n and not self.wanted()

    def add_run(self, i: int, mode: str, result: Executed, cpu: float) -> None:
        self.cpu += cpu
        by_mode = self.runs.setdefault(i, {})
        by_mode[mode] = result
        if all(m in by_mode for m in MODES):
            self.executed[i] = Executions(**{m: by_mode[m].error for m in MODES},
                                          status={m: by_mode[m].status for m in MODES})


def _work(cands: Sequence[Candidate], pool: Executor | None, workers: int, budget: float, execute_all: bool,
          seed: int, say: Callable[[str], None]) -> _Work:
    """Plan every candidate and execute the solved plans (module docstring). In a pool, the plans go
    first and the executions fill the slots the plans leave free, so the executions of the plans solved
    early overlap the planning of the slow candidates (those without a plan, whose certificate searches
    take longest)."""
    w = _Work(len(cands), execute_all)
    if pool is None:
        for i, c in enumerate(cands):
            w.planned[i] = plan_candidate(c.task, budget)
        while not w.done():
            i, mode = w.wanted()[0]
            say(f"executing {mode.replace('_', ' ')} of {cands[i].label}")
            w.add_run(i, mode, execute(w.plan(i), mode, seed), 0.0)  # its CPU time is this process's
        return w
    to_plan = list(range(len(cands)))
    inflight: dict[Future, tuple[int, str]] = {}  # (candidate, "plan" or an execution mode)
    while not w.done():
        busy = set(inflight.values())
        queue = [(i, "plan") for i in to_plan] + [job for job in w.wanted() if job not in busy]
        for i, what in queue[:max(0, workers - len(inflight))]:
            if what == "plan":
                to_plan.remove(i)
                inflight[pool.submit(plan_candidate, cands[i].task, budget)] = (i, what)
            else:
                inflight[pool.submit(_timed_execute, w.plan(i), what, seed)] = (i, what)
        if not inflight:  # pragma: no cover - done() would hold
            break
        finished, _ = wait(list(inflight), return_when=_FIRST)
        for f in finished:
            i, what = inflight.pop(f)
            if what == "plan":
                p = f.result()
                w.planned[i] = p
                w.cpu += p.cpu
                say(f"{len(w.planned)}/{len(cands)} planned ({cands[i].label}: {p.verdict})")
            else:
                result, used = f.result()
                w.add_run(i, what, result, used)
                say(f"{cands[i].label}: {what.replace('_', ' ')} {result.status}")
    return w


def _timed_execute(plan: Plan, mode: str, seed: int) -> tuple[Executed, float]:
    t = time.process_time()
    out = execute(plan, mode, seed)
    return out, time.process_time() - t


def _rank(cands: Sequence[Candidate], planned: Sequence[Planned], runs: dict[int, dict[str, Executed]],
          executed: dict[int, Executions]) -> list[Ranked]:
    """The candidates best first (:func:`.ranking.rank_key`); ``executed``: the plans every execution of
    which ran, ``runs``: every execution run (a plan whose executions were cut short keeps none)."""
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
                   planning_cpu=planned[i].cpu) for n, i in enumerate(order)]
