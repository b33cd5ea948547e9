"""The work of one tool choice: planning every candidate and executing the solved plans, in a pool.

A choice makes two pools: the planners, a process per candidate (:func:`processes`: at most
:data:`PROCESSES_PER_WORKER` per worker), all planning from the start while the operating system
shares the cores among them, and :func:`run_processes` that execute the solved plans. A tool that
solves the task so has its plan (0.6 s of CPU on the library's tools) while the slow candidates are
still in their searches, instead of waiting for a slot they hold (the planner's budgets count
expansions and updates, not time, so a verdict does not depend on how the cores are shared). The
planners keep the normal priority until the first plan is executed, then become :data:`PLAN_NICE`
nicer, so that the best plan's executions take the cores from the candidates still planning (by then
mostly the slow ones the deadline stops); not from the start, since a lower priority starves the
planners behind any other work on the machine (measured: a 0.6 s plan took 15 s at ``nice`` 10
beside six other processes).

**Quick and slower stages.** Each planning process says when its candidate's quick first stage (the
variant's condensing: the scored push sequences) found no plan and its slower stages begin (the guided
search, the infeasibility certificate: ``solve``'s ``on_slow``), in flags shared with the processes
forked after they are made (:func:`slow_flags`). A tool that solves the task mostly solves it on its
quick stage (0.6 s of CPU on the library's tools); a candidate in its slower stages takes 5-40 s of
CPU and ends mostly in ``unknown`` or ``infeasible``.

**The executions** (:mod:`.executions`) start once fewer candidates are on their quick stage than
``workers`` (a core is free of them), or :func:`grace` after the first solved plan (the larger of
:data:`GRACE_MIN` and the planning wall time of the first candidate that solved the task), whichever
comes first; best plan first (:func:`.ranking.plan_order`), a plan's three executions at once
(:func:`run_processes`), the next plan's only once it failed one; with one pool given
(``executor``), ``workers`` jobs run in all, plans first. Only the plans that may still be the best
are executed (:func:`.ranking.needs_execution`; ``execute_all``: every solved plan). The executions
started beside the quick stages slowed them (measured 2026-12-04, 30 tasks of six tools: wall median
3.81 s with the executions at the first plan, 2.6-3.1 s waiting as here); the 1 s floor covers a first
plan solved in less time than a process needs to be scheduled on a loaded machine.

**The deadline.** Once the best plan so far has passed every execution (:func:`.ranking.known_best`:
every plan ranked above it by margins was executed and failed one), the candidates in their slower
stages (and any not yet started) are stopped, and a candidate still on its quick stage is waited for;
where the stages are not known (processes not forked from here) every candidate still planning is
stopped. A stopped candidate's process is ended with the pools' and its verdict is ``unknown``, the
reason :func:`stopped_reason` (never ``infeasible`` nor ``solved``: nothing was decided). Its verdict
mostly cannot change the choice (a candidate without a plan ranks below any solved one), but the
slower stages solve some tasks, and such a plan might rank above the one chosen by margins and
duration (which passed every execution all the same): of 40 candidates stopped on 30 tasks of six
tools, 15 would have been solved and 2 of those chosen instead (``benchmarks/README.md``).
``wait_all`` is for a choice that must rank every tool: it waits for every verdict, and so does a
choice no plan of which passed every execution (nothing is then stopped), one run in this process
(``workers=1``: the candidates are planned one after the other before any execution) and one in a
pool it was given (its processes are not this choice's to end).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED as _FIRST
from concurrent.futures import Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from typing import Any

from tooltransfer.planner.apps.choose.candidates import Candidate
from tooltransfer.planner.apps.choose.executions import MODES, Executed, Planned, execute, plan_candidate
from tooltransfer.planner.apps.choose.ranking import (
    Executions,
    execution_passed,
    known_best,
    needs_execution,
    plan_order,
)
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.problems.task import Task

#: The order in which one plan's executions are handed out (the longest first: two slots finish together).
_SUBMIT_ORDER = ("closed_loop", "mismatch_closed_loop", "open_loop")
#: The most processes of a pool per worker (the cores a choice uses).
PROCESSES_PER_WORKER = 5
#: How much nicer the planning processes become once the first plan is executed (module docstring).
PLAN_NICE = 10
#: The shortest grace [s] the candidates still planning get once a plan passed every execution.
GRACE_MIN = 1.0


#: Per candidate of the choice being worked, 1 once its planning began its slower stages (``solve``'s
#: ``on_slow``: no plan from the variant's condensing), in memory shared with the planning processes
#: forked after it is made (:func:`slow_flags`; None where they are not forked from this process).
_SLOW: Any = None


def slow_flags(n: int) -> Any:
    """Flags shared with the planning processes forked from now on, one per candidate of ``n``, made
    the module's :data:`_SLOW`; None (and :data:`_SLOW` None) where processes are not forked here."""
    import multiprocessing

    global _SLOW
    _SLOW = multiprocessing.RawArray("b", n) if "fork" in multiprocessing.get_all_start_methods() else None
    return _SLOW


def _plan_job(task: Task, budget: float, index: int) -> Planned:
    """Plan candidate ``index`` in a planning process (:func:`.executions.plan_candidate`), its flag of
    :data:`_SLOW` set once the slower stages begin."""
    flags = _SLOW

    def mark() -> None:
        if flags is not None:
            flags[index] = 1

    return plan_candidate(task, budget, mark)


def grace(first_solved_wall: float) -> float:
    """The grace [s] of the candidates still planning (module docstring): the larger of
    :data:`GRACE_MIN` and ``first_solved_wall``, the planning wall time [s] of the first candidate
    that solved the task."""
    return max(GRACE_MIN, first_solved_wall)


def stopped_reason(best: str) -> str:
    """The reason of a candidate stopped at the deadline, ``best`` the candidate that passed."""
    return f"stopped after {best} passed every execution; `--wait-all` waits for its verdict"


@dataclass(frozen=True)
class Options:
    """How one choice works: the planner's ``budget``, the closed loops' ``seed``, whether every solved
    plan is executed (``execute_all``), whether every verdict is waited for (``wait_all``)."""

    budget: float = 1.0
    seed: int = 0
    execute_all: bool = False
    wait_all: bool = False


def processes(workers: int, candidates: int) -> int:
    """The processes of a choice's pool on ``workers`` cores for ``candidates`` tools: one per candidate,
    at least ``workers`` and at most :data:`PROCESSES_PER_WORKER` per worker."""
    return max(workers, min(candidates, PROCESSES_PER_WORKER * workers))


def run_processes(workers: int) -> int:
    """The processes of a choice's pool of executions on ``workers`` cores: at least one per execution of
    a plan (:data:`.executions.MODES`), so that a plan's three executions run at once (on two cores they
    end together, instead of the open loop waiting for a closed loop's core: measured 2026-12-04 on
    ``choose100-00016``, 1.0 -> 0.9 s from the first execution's start to the last one's end), and at
    least ``workers``."""
    return max(workers, len(MODES))


def pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes, forked from this one where the platform allows."""
    import multiprocessing

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    return ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method))


@dataclass(frozen=True)
class Pools:
    """Where a choice's jobs run: the candidates' planning in ``plan``, at most ``plan_slots`` at a time,
    the executions in ``run``, at most ``run_slots``; ``own``: this choice's pools (two: the planners,
    a process per candidate, and :func:`run_processes` executing), which
    :meth:`stop` ends; else one pool the caller gave, ``plan_slots`` jobs in all, plans first."""

    plan: Executor
    run: Executor
    plan_slots: int
    run_slots: int
    own: bool
    cores: int = 1

    @classmethod
    def make(cls, workers: int, candidates: int) -> Pools:
        """This choice's pools on ``workers`` cores for ``candidates`` tools (module docstring)."""
        n, m = processes(workers, candidates), run_processes(workers)
        return cls(pool(n), pool(m), n, m, True, workers)

    @classmethod
    def given(cls, executor: Executor, workers: int) -> Pools:
        return cls(executor, executor, workers, workers, False, workers)

    def yield_to_executions(self) -> None:
        """Lower the planning processes' priority by :data:`PLAN_NICE` (this choice's own pools, where
        the platform can): called when the first execution starts (module docstring)."""
        if not self.own:
            return
        for proc in list((getattr(self.plan, "_processes", None) or {}).values()):
            try:
                os.setpriority(os.PRIO_PROCESS, proc.pid, os.getpriority(os.PRIO_PROCESS, proc.pid) + PLAN_NICE)
            except (AttributeError, OSError):  # pragma: no cover - no priorities here, or the process ended
                pass

    def stop(self) -> None:
        """End this choice's own pools, together (:func:`stop`); a pool given is left open."""
        if self.own:
            stop(*(p for p in (self.plan, self.run) if isinstance(p, ProcessPoolExecutor)))


def stop(*pools: ProcessPoolExecutor) -> None:
    """End pools this choice made now: jobs queued are dropped, running ones (executions no longer
    needed, candidates stopped at the deadline) are ended with their processes, and every process is
    waited for (none is left behind, and its CPU time is counted: :func:`children_cpu`).

    The pools are ended together: a worker ended while it sends its result (a plan is some hundred kB)
    leaves a part of a message in its pool's result pipe, and the pool's own thread, reading it, waits
    for the rest for as long as the pipe has a writer. Every process of both pools holds the write
    ends of both (they are forked once both pools exist), and this process holds one; so every
    process is ended first, then this process's write ends are closed, and the reading thread gets
    the pipe's end instead of waiting (measured before: a choice's ``stop`` took the 30 s it waits for
    that thread, which then held the interpreter's exit for good)."""
    procs = [proc for p in pools for proc in list((getattr(p, "_processes", None) or {}).values())]
    # the pools' own threads, which also wait for their processes: the first shutdown forgets them, so that
    # the second would not wait for them; joined here, each has recorded the exit of every process it reaped
    # (a process it reaped and this thread then polled looks running to this one until it has)
    managers = [getattr(p, "_executor_manager_thread", None) for p in pools]
    writers = [getattr(getattr(p, "_result_queue", None), "_writer", None) for p in pools]
    for p in pools:
        p.shutdown(wait=False, cancel_futures=True)
    for proc in procs:
        if proc.is_alive():
            proc.terminate()
    for proc in procs:
        proc.join(5.0)
        if proc.exitcode is None:  # a process that ignores SIGTERM, or one the pool's thread is reaping
            proc.kill()
            proc.join(5.0)
    for writer in writers:
        if writer is not None:
            writer.close()
    for manager in managers:
        if manager is not None:
            manager.join(30.0)
    for p in pools:
        p.shutdown(wait=True)


def children_cpu() -> float | None:
    """The CPU time [s] (user and system) of this process's ended and waited-for child processes
    (None where the platform does not say)."""
    try:
        import resource
    except ImportError:  # pragma: no cover - not on POSIX
        return None
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


#: The modules the pool's jobs use, imported before the processes fork (each would import them again).
_JOB_MODULES = ("tooltransfer.planner.planning.solve", "tooltransfer.planner.planning.verdicts.certificate",
                "tooltransfer.planner.execution.closed_loop", "tooltransfer.planner.execution.simulate",
                "tooltransfer.planner.execution.plant", "tooltransfer.planner.planning.oe.correction",
                "tooltransfer.tools.pushing.adaptation", "tooltransfer.tools.sim.platform", "scipy.optimize")


def warm(task: Task) -> None:
    """Learn (or read from the cache) the task's skills here, and import the modules the jobs use
    (:data:`_JOB_MODULES`: the planner, the closed loop, MuJoCo), before the pool's processes fork:
    no process learns, loads or imports them again."""
    import importlib

    from tooltransfer.planner.planning.setting import task_skills
    from tooltransfer.planner.planning.variant_registry import needs_ss_skill

    task_skills(task, need_ss=needs_ss_skill(task.variants.ss))
    for name in _JOB_MODULES:
        importlib.import_module(name)


class Work:
    """The state of one choice's work: the plans and executions done, and what to run next."""

    def __init__(self, labels: Sequence[str], options: Options) -> None:
        self.labels = list(labels)
        self.n = len(labels)
        self.options = options
        self.planned: dict[int, Planned] = {}
        self.runs: dict[int, dict[str, Executed]] = {}
        self.executed: dict[int, Executions] = {}
        self.cpu = 0.0  # of the jobs [s]
        self.first_solved_wall: float | None = None  # planning wall [s] of the first candidate solved
        self.first_solved_at: float | None = None  # perf_counter [s] at which it was recorded
        self.deadline: float | None = None  # perf_counter [s] at which the candidates still planning stop
        self.stopped: list[int] = []
        self.slow: Any = None  # the candidates' shared flags (slow_flags), None where not known
        self.cores = 1  # the cores the choice's jobs share
        self.started: dict[int, float] = {}  # when each candidate was handed to the planners, perf_counter [s]

    def order(self) -> list[int]:
        """The solved candidates planned so far, by their plans' margins and duration (best first)."""
        solved = [i for i in sorted(self.planned) if self.planned[i].verdict == "solved"
                  and self.planned[i].plan is not None]
        return [solved[k] for k in plan_order([("solved", self.plan(i).metrics) for i in solved])]

    def plan(self, i: int) -> Plan:
        plan = self.planned[i].plan
        assert plan is not None  # only solved candidates with a plan are executed
        return plan

    def best(self) -> int | None:
        """The candidate known to be the best of those planned so far (:func:`.ranking.known_best`)."""
        return known_best(self.order(), self.executed)

    def wanted(self) -> list[tuple[int, str]]:
        """The executions still to run, best candidate first (:func:`.ranking.needs_execution`): a plan's
        only once every plan before it failed one (the first usually passes them all, and executions
        run on the off chance took its cores: measured on ``choose100-00016``); with ``execute_all``
        every solved plan's."""
        order = self.order()
        if self.options.execute_all:
            return [(i, m) for i in order if i not in self.executed for m in _SUBMIT_ORDER
                    if m not in self.runs.get(i, {})]
        out: list[tuple[int, str]] = []
        for i in needs_execution(order, self.executed):
            runs = self.runs.get(i, {})
            out += [(i, m) for m in _SUBMIT_ORDER if m not in runs]
            if all(execution_passed(m, r.error) for m, r in runs.items()):
                break  # the plans behind it wait until it fails an execution
        return out

    def done(self) -> bool:
        return len(self.planned) == self.n and not self.wanted()

    def add_plan(self, i: int, p: Planned) -> None:
        self.planned[i] = p
        self.cpu += p.cpu
        if p.verdict == "solved" and self.first_solved_wall is None:
            self.first_solved_wall = p.wall
            self.first_solved_at = time.perf_counter()

    def executions_from(self) -> float | None:
        """When [s, perf_counter] the executions may start beside the candidates still planning: the
        :func:`grace` after the first solved plan (None before one; every candidate planned opens them
        at once, :meth:`executions_open`)."""
        if self.first_solved_at is None:
            return None
        return self.first_solved_at + grace(self.first_solved_wall or 0.0)

    def executions_open(self) -> bool:
        """Whether the executions may run (module docstring): fewer candidates on their quick first stage
        than :attr:`cores` (a core free of them), or the grace after the first solved plan over."""
        start = self.executions_from()
        if start is None:
            return len(self.planned) == self.n
        return self.quick() < self.cores or time.perf_counter() >= start

    def quick(self) -> int:
        """How many candidates still planning may yet find a plan on their quick first stage (those not
        started, or not known to be in their slower stages)."""
        return sum(i not in self.planned and not self.in_slow_stages(i) for i in range(self.n))

    def in_slow_stages(self, i: int) -> bool:
        """Whether candidate ``i``, still planning, has begun its slower stages (never where not known)."""
        return self.slow is not None and i in self.started and bool(self.slow[i])

    def due(self) -> list[int]:
        """The candidates to stop now: none before the deadline; after it those still planning in their
        slower stages and those not started, or every one still planning where the stages are not known."""
        if self.deadline is None:
            return []
        pending = [i for i in range(self.n) if i not in self.planned]
        if self.slow is None:
            return pending
        return [i for i in pending if i not in self.started or self.in_slow_stages(i)]

    def add_run(self, i: int, mode: str, result: Executed, cpu: float) -> None:
        self.cpu += cpu
        by_mode = self.runs.setdefault(i, {})
        by_mode[mode] = result
        if all(m in by_mode for m in MODES):
            self.executed[i] = Executions(**{m: by_mode[m].error for m in MODES},
                                          status={m: by_mode[m].status for m in MODES})

    def set_deadline(self, stoppable: bool, say: Callable[[str], None]) -> None:
        """Set the deadline of the candidates still planning once a plan passed every execution
        (module docstring), where they can be stopped and ``wait_all`` is not asked for."""
        if not stoppable or self.options.wait_all or self.deadline is not None or len(self.planned) == self.n:
            return
        best = self.best()
        if best is None:
            return
        self.deadline = time.perf_counter()
        say(f"{self.labels[best]} passed every execution: the candidates still planning are stopped "
            + ("once in their slower stages" if self.slow is not None else "now"))

    def stop_planning(self, which: Sequence[int]) -> None:
        """The candidates ``which`` (not yet planned) become ``unknown``, stopped; their CPU time is not
        known here (the choice's counts it)."""
        best = self.best()
        name = self.labels[best] if best is not None else "the best plan"
        now = time.perf_counter()
        for i in which:
            self.planned[i] = Planned(None, "unknown", stopped_reason(name), now - self.started.get(i, now), 0.0)
            self.stopped.append(i)


def work(cands: Sequence[Candidate], pools: Pools | None, options: Options, say: Callable[[str], None]) -> Work:
    """Plan every candidate and execute the solved plans (module docstring) in ``pools`` (None: in this
    process); the deadline applies to this choice's own pools (their processes :func:`stop` ends)."""
    w = Work([c.label for c in cands], options)
    if pools is None:
        for i, c in enumerate(cands):
            w.add_plan(i, plan_candidate(c.task, options.budget))
        while not w.done():
            i, mode = w.wanted()[0]
            say(f"executing {mode.replace('_', ' ')} of {cands[i].label}")
            w.add_run(i, mode, execute(w.plan(i), mode, options.seed), 0.0)  # its CPU time is this process's
        return w
    to_plan = list(range(len(cands)))
    w.cores = pools.cores
    if pools.own:  # before any planning process is forked
        w.slow = slow_flags(len(cands))
    inflight: dict[Future, tuple[int, str]] = {}  # (candidate, "plan" or an execution mode)
    yielded = False
    while not w.done():
        for i, what in _next_jobs(w, pools, to_plan, inflight):
            if what == "plan":
                to_plan.remove(i)
                w.started[i] = time.perf_counter()
                inflight[pools.plan.submit(_plan_job, cands[i].task, options.budget, i)] = (i, what)
            else:
                if not yielded:  # the first execution: the planners make way
                    pools.yield_to_executions()
                    yielded = True
                inflight[pools.run.submit(_timed_execute, w.plan(i), what, options.seed)] = (i, what)
        if not inflight:  # pragma: no cover - done() would hold
            break
        finished, _ = wait(list(inflight), timeout=_timeout(w), return_when=_FIRST)
        for f in finished:
            _take(w, cands, inflight.pop(f), f, say)
        w.set_deadline(pools.own, say)
        due = w.due()
        if due:
            w.stop_planning(due)
            say(f"stopped {len(due)} candidates still planning")
            for i in due:
                if i in to_plan:
                    to_plan.remove(i)
            for f, (i, what) in list(inflight.items()):
                if what == "plan" and i in due:  # its process is ended with the pool's (stop)
                    del inflight[f]
    return w


#: How often [s] the candidates' stages are looked at while a change of one would start the executions or
#: stop a candidate.
POLL = 0.05


def _timeout(w: Work) -> float | None:
    """How long [s] to wait for a job to end before looking again: until the grace after the first solved
    plan is over (the executions may start), or :data:`POLL` where a candidate entering its slower
    stages would start them or stop it; None: until a job ends."""
    closed = w.deadline is None and not w.executions_open()  # the executions may yet start
    waits = [POLL] if w.slow is not None and w.quick() > 0 and (w.deadline is not None or closed) else []
    start = w.executions_from()
    if closed and start is not None:
        waits.append(max(0.0, start - time.perf_counter()))
    return min(waits, default=None)


def _next_jobs(w: Work, pools: Pools, to_plan: list[int],
               inflight: dict[Future, tuple[int, str]]) -> list[tuple[int, str]]:
    """The jobs to hand out now: plans first, then the executions wanted, each kind up to its slots
    (one pool given: ``plan_slots`` jobs in all)."""
    busy = set(inflight.values())
    plans = [(i, "plan") for i in to_plan]
    runs = [job for job in w.wanted() if job not in busy]
    if not pools.own:
        return (plans + runs)[:max(0, pools.plan_slots - len(inflight))]
    n_plans = sum(what == "plan" for _, what in busy)
    n_runs = len(busy) - n_plans
    if not w.executions_open():
        runs = []
    return plans[:max(0, pools.plan_slots - n_plans)] + runs[:max(0, pools.run_slots - n_runs)]


def _take(w: Work, cands: Sequence[Candidate], job: tuple[int, str], f: Future, say: Callable[[str], None]) -> None:
    """Record the finished job ``job`` (candidate, ``"plan"`` or an execution mode) of future ``f``."""
    i, what = job
    if what == "plan":
        p: Planned = f.result()
        w.add_plan(i, p)
        say(f"{len(w.planned)}/{len(cands)} planned ({cands[i].label}: {p.verdict})")
    else:
        result, used = f.result()
        w.add_run(i, what, result, used)
        say(f"{cands[i].label}: {what.replace('_', ' ')} {result.status}")


def _timed_execute(plan: Plan, mode: str, seed: int) -> tuple[Executed, float]:
    t = time.process_time()
    out = execute(plan, mode, seed)
    return out, time.process_time() - t

