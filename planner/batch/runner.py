"""Running a batch: jobs to an executor, rows to the store as each job finishes, progress, Ctrl-C.

One code path for the process pool and Dask (:mod:`planner.batch.executors`): at most two jobs per
slot are in flight; each finished future's row is committed at once. ``resume`` skips the
(task, variant) pairs already stored; without it a store that already holds rows is refused. The
first Ctrl-C (SIGINT) stops submitting, cancels what has not started, waits for the running jobs
(each is bounded by its timeout) and stores them; a second Ctrl-C abandons them. Either way the
store holds only whole rows and ``--resume`` carries on. A broken process pool (a worker killed
from outside) is replaced and its running jobs are run again once, each alone (so that the job
that breaks it again is the culprit, and the others are not charged for it); a job that breaks the
pool running alone, or whose Dask worker died, becomes an ``error`` row. With simulation
(``--simulate`` or ``simulate.enabled``) each solved plan is also executed open and closed loop in
the same slot's sandbox, each execution with its own timeout; whether plans are executed is
recorded in the store and a resume with the other setting is refused.
"""

from __future__ import annotations

import json
import signal
import threading
import time
from collections import Counter
from collections.abc import Sequence
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    ProgressColumn,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.text import Text

from dmp.errors import InputError
from planner.batch.executors import Slots
from planner.batch.generate import GeneratedTask, generate_tasks
from planner.batch.spec import BatchSpec
from planner.batch.store import ResultStore
from planner.batch.worker import Job, Stage, run_job

STATUSES = ("solved", "violated", "infeasible", "error", "timeout")


@dataclass
class RunSummary:
    """What a run did.

    Attributes:
        total: (task, variant) pairs in the batch.
        skipped: pairs already in the store (resume).
        counts: rows stored by this run, per status.
        interrupted: stopped by Ctrl-C before the end.
        wall: wall time of the run [s] (after the warm-up).
        slots: parallel jobs.
        kind: executor kind.
    """

    total: int
    skipped: int
    counts: Counter = field(default_factory=Counter)
    interrupted: bool = False
    wall: float = 0.0
    slots: int = 1
    kind: str = ""

    @property
    def stored(self) -> int:
        return sum(self.counts.values())

    @property
    def throughput(self) -> float:
        """Rows per second per slot (core) in this run."""
        return self.stored / self.wall / self.slots if self.wall > 0 else 0.0


class _Rate(ProgressColumn):
    def render(self, task: Any) -> Text:
        speed = task.finished_speed or task.speed
        return Text(f"{speed:.2f}/s" if speed else "-/s", style="progress.data.speed")


def simulate_setting(spec: BatchSpec, simulate: bool | None = None) -> bool:
    """Whether solved plans are executed: ``simulate`` (``--simulate``/``--no-simulate``), else the
    batch file's ``simulate.enabled``."""
    return spec.simulate.enabled if simulate is None else bool(simulate)


def batch_jobs(spec: BatchSpec, batch_path: str | Path, tasks: Sequence[GeneratedTask] | None = None,
               timeout: float | None = None, simulate: bool | None = None) -> tuple[list[GeneratedTask], list[Job]]:
    """The batch's tasks and its jobs (every task with every variant), in task order. With
    simulation, each job executes its solved plan open loop and closed loop in two more sandbox
    calls (:class:`planner.batch.worker.Stage`, ``simulate.timeout`` each), the closed loop with task
    ``i``'s camera-noise seed (:meth:`planner.batch.spec.Simulation.closed_loop_seed`)."""
    tasks = list(tasks) if tasks is not None else generate_tasks(spec, batch_path)
    sim = simulate_setting(spec, simulate)
    cfg = spec.simulate
    limit = spec.timeout if timeout is None else timeout
    source = str(Path(batch_path).resolve())
    pairs = spec.variants.pairs()
    warm: list[tuple[str, tuple]] = [("planner.batch.execute:warm_up", (sim,))]
    if tasks:
        warm += [("planner.batch.execute:execute_job", (tasks[0].data, source, oe, ss, False)) for oe, ss in pairs]
    jobs = []
    for t in tasks:
        stages: tuple[Stage, ...] = ()
        if sim:
            stages = (Stage("open_loop", "planner.batch.execute:open_loop", (cfg.tolerance,), cfg.timeout),
                      Stage("closed_loop", "planner.batch.execute:closed_loop",
                            (cfg.closed_loop_seed(t.index), cfg.closed_loop_tolerance, cfg.camera_noise), cfg.timeout))
        jobs += [Job(t.task_id, f"{oe}/{ss}", args=(t.data, source, oe, ss, sim), timeout=limit, warmup=tuple(warm),
                     stages=stages) for oe, ss in pairs]
    return tasks, jobs


def task_records(tasks: Sequence[GeneratedTask]) -> list[dict[str, Any]]:
    """Rows of the store's ``tasks`` table."""
    return [{"task_id": t.task_id, "idx": t.index, "tool": t.tool, "n_obstacles": t.n_obstacles,
             "start_reach": t.start_reach, "target_reach": t.target_reach, "reach_margin": t.reach_margin,
             "distance": t.distance, "task_json": json.dumps(t.data)} for t in tasks]


def _on_off(v: bool) -> str:
    return "on" if v else "off"


def open_batch_store(store: ResultStore, spec: BatchSpec, tasks: Sequence[GeneratedTask], resume: bool,
                     simulate: bool | None = None) -> None:
    """Tie ``store`` to the batch and its settings, refusing: a file of an older schema, another
    batch's store, a filled one without ``resume``, and one filled with the other execution setting
    (``simulate``, default the batch file's: see :func:`simulate_setting`)."""
    from planner.batch.store import SCHEMA_VERSION

    if store.schema != SCHEMA_VERSION:
        raise InputError("--db", f"a results file of schema {SCHEMA_VERSION} to resume, or a new file",
                         f"{store.path} of schema {store.schema} (written before executions were stored; "
                         "`tooltransfer batch report` still reads it)")
    meta = store.meta()
    digest = spec.digest()
    if meta.get("batch_digest") not in (None, digest):
        raise InputError("--db", f"a results file of this batch ({spec.name}, {digest}) or a new file",
                         f"{store.path} holds batch {meta.get('batch_name')} ({meta.get('batch_digest')})")
    n = store.count()
    if n and not resume:
        raise InputError("--resume", f"--resume to carry on ({store.path} already holds {n} results) "
                         "or a new --db", "neither")
    sim = _on_off(simulate_setting(spec, simulate))
    was = meta.get("simulate")
    if n and was not in (None, sim):
        how = {"on": "--simulate, or simulate.enabled: true in the batch file",
               "off": "--no-simulate, or simulate.enabled: false in the batch file without --simulate"}
        raise InputError("--simulate", f"the setting {store.path} was run with, simulate {was} ({how[was]})",
                         f"simulate {sim}: resume with the same setting, or run into a new --db")
    store.set_meta(batch_name=spec.name, batch_digest=digest, batch=spec.model_dump_json(), simulate=sim)
    store.add_tasks(task_records(tasks))


def run_jobs(jobs: Sequence[Job], store: ResultStore, slots: Slots, *, info: dict[tuple[str, str], dict] | None = None,
             progress: bool = True, console: Console | None = None, stop: threading.Event | None = None,
             catch_sigint: bool = True) -> RunSummary:
    """Run the jobs not yet stored, storing each row as it finishes (see the module docstring).

    Args:
        info: extra fields per key (e.g. tool, oe, ss) added to each row.
        stop: set it to stop as on Ctrl-C.
    """
    info = info or {}
    done = store.done()
    todo = [j for j in jobs if j.key not in done]
    summary = RunSummary(total=len(jobs), skipped=len(jobs) - len(todo), slots=slots.slots, kind=slots.kind)
    stop = stop or threading.Event()
    aborted = False
    previous = None

    def on_sigint(signum: int, frame: object) -> None:
        nonlocal aborted
        if stop.is_set():
            aborted = True
            raise KeyboardInterrupt
        stop.set()

    if catch_sigint and threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGINT, on_sigint)
    console = console or Console(stderr=True)
    bar = Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TaskProgressColumn(),
                   _Rate(), TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn(),
                   TextColumn("{task.fields[counts]}"), console=console, disable=not progress, transient=False)
    queue = list(reversed(todo))
    attempts: Counter = Counter()
    inflight: dict[Future, tuple[Job, Any]] = {}  # future -> (job, the executor it went to)
    window = 2 * max(1, slots.slots)
    start = time.perf_counter()

    def store_row(job: Job, row: dict[str, Any]) -> None:
        row = {**info.get(job.key, {}), **row, "task_id": job.task_id, "variant": job.variant}
        store.put(row)
        summary.counts[row["status"]] += 1

    try:
        with bar:
            t = bar.add_task("batch", total=len(todo), counts="")
            while queue or inflight:
                while queue and not stop.is_set() and len(inflight) < window:
                    # a job that was running when the pool broke is a suspect: it runs alone, so a job
                    # that breaks the pool again is the culprit and the others are not charged for it
                    if any(attempts[j.key] for j, _ in inflight.values()):
                        break
                    if attempts[queue[-1].key] and inflight:
                        break
                    job = queue.pop()
                    try:
                        inflight[slots.executor.submit(run_job, job)] = (job, slots.executor)
                    except BrokenProcessPool:
                        queue.append(job)
                        slots.renew()
                if stop.is_set():
                    if queue and progress:
                        console.print(f"stopping: finishing {len(inflight)} running jobs (Ctrl-C again to abandon "
                                      "them); the store can be resumed")
                    for f in [f for f in inflight if f.cancel()]:
                        inflight.pop(f)
                    queue.clear()
                    if not inflight:
                        break
                finished, _ = wait(list(inflight), timeout=0.25, return_when=FIRST_COMPLETED)
                broken = False
                for f in finished:
                    job, executor = inflight.pop(f)
                    try:
                        row = f.result()
                    except CancelledError:
                        if not stop.is_set():
                            queue.append(job)  # cancelled by a pool replacement, never run
                        continue
                    except BrokenProcessPool:
                        broken = broken or executor is slots.executor  # a pool already replaced is not renewed
                        attempts[job.key] += 1
                        if attempts[job.key] < 2 and not stop.is_set():
                            queue.append(job)
                            continue
                        if stop.is_set():
                            continue
                        row = {"status": "error", "reason": "the worker process died twice while running this job",
                               "finished_at": time.time()}
                    except Exception as exc:  # the executor's own failure for this job (e.g. KilledWorker)
                        if stop.is_set():
                            continue  # not stored: run again on resume
                        row = {"status": "error", "reason": f"{type(exc).__name__}: {exc}", "finished_at": time.time()}
                    store_row(job, row)
                    bar.update(t, advance=1, counts=" ".join(f"{s} {summary.counts[s]}" for s in STATUSES
                                                             if summary.counts[s]))
                if broken:
                    slots.renew()
    except KeyboardInterrupt:
        aborted = True
        slots.abandon()
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    summary.wall = time.perf_counter() - start
    summary.interrupted = aborted or stop.is_set()
    return summary


def run_batch(batch_path: str | Path, db: str | Path, *, workers: int | None = None, scheduler: str | None = None,
              dask_local: int | None = None, timeout: float | None = None, simulate: bool | None = None,
              resume: bool = False, retry: Sequence[str] = (), progress: bool = True,
              console: Console | None = None) -> RunSummary:
    """Generate the batch's tasks and run every (task, variant) not yet in the store ``db``.

    Args:
        workers: process-pool size (default: the CPU count).
        scheduler, dask_local: run on a Dask cluster instead (see :func:`planner.batch.executors.open_executor`).
        timeout: per job [s] (default: the batch file's).
        simulate: override the batch file's ``simulate.enabled`` (part of the store's settings: a resume
            with the other setting is refused).
        resume: carry on a store that already holds rows of this batch.
        retry: statuses to run again on resume (e.g. ``("error", "timeout")``).
    """
    from planner.batch.executors import open_executor
    from planner.batch.spec import load_batch

    if timeout is not None and not timeout > 0:
        raise InputError("--timeout", "a positive number of seconds", timeout)
    spec = load_batch(batch_path)
    tasks, jobs = batch_jobs(spec, batch_path, timeout=timeout, simulate=simulate)
    console = console or Console(stderr=True)
    with ResultStore(db) as store:
        open_batch_store(store, spec, tasks, resume, simulate)
        if retry:
            store.forget(retry)
        if len(store.done()) < len(jobs):
            _warm_parent(jobs, console, progress)
        tool = {t.task_id: t.tool for t in tasks}
        info = {j.key: {"tool": tool[j.task_id], "oe": j.args[2], "ss": j.args[3]} for j in jobs}
        with open_executor(workers, scheduler, dask_local) as slots:
            if progress:
                ex = ", solved plans executed open and closed loop" if simulate_setting(spec, simulate) else ""
                console.print(f"batch {spec.name}: {len(tasks)} tasks x {len(spec.variants.pairs())} variants{ex} "
                              f"on a {slots.kind} ({slots.where}), results in {store.path}")
            return run_jobs(jobs, store, slots, info=info, progress=progress, console=console)


def _warm_parent(jobs: Sequence[Job], console: Console, progress: bool) -> None:
    """Learn the skills once here (the disk cache then serves every sandbox): one job per variant."""
    from planner.batch.execute import execute_job

    seen = set()
    for j in jobs:
        if j.variant in seen:
            continue
        seen.add(j.variant)
        if progress:
            console.print(f"warming up: skills and solver for {j.variant} ...")
        try:
            execute_job(*j.args[:4])
        except Exception:  # the same job will run (and report) in the batch
            pass
