"""Running a batch: jobs to an executor, rows to the store as each job finishes, progress, Ctrl-C.

One code path for the process pool and Dask (:mod:`tooltransfer.planner.apps.batch.executors`): at most two jobs per
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

The skills travel with the run (:mod:`tooltransfer.planner.apps.batch.shipping`): learned once here from the batch's
dataset and shipped to the executor (a file the pool's workers read, a plugin that writes it on every
Dask worker), every job planning with that copy; the workers need this package, not the dataset.
"""

from __future__ import annotations

import json
import signal
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

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

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.executors import Slots
from tooltransfer.planner.apps.batch.generate import GeneratedTask, generate_tasks
from tooltransfer.planner.apps.batch.spec import BatchSpec
from tooltransfer.planner.apps.batch.store import ResultStore
from tooltransfer.planner.apps.batch.worker import Job, Stage, run_job

if TYPE_CHECKING:
    from tooltransfer.planner.apps.batch.shipping import ShippedSkills

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
    calls (:class:`tooltransfer.planner.apps.batch.worker.Stage`, ``simulate.timeout`` each), the closed loop with task
    ``i``'s camera-noise seed (:meth:`tooltransfer.planner.apps.batch.spec.Simulation.closed_loop_seed`). (Every task
    up front: :func:`run_batch` generates them as it runs.)"""
    tasks = list(tasks) if tasks is not None else generate_tasks(spec, batch_path)
    warm = _warmup(spec, batch_path, tasks[0] if tasks else None, simulate)
    return tasks, [j for t in tasks for j in task_jobs(spec, batch_path, t, timeout, simulate, warm)]


def _warmup(spec: BatchSpec, batch_path: str | Path, first: GeneratedTask | None,
            simulate: bool | None) -> tuple[tuple[str, tuple], ...]:
    """The calls a new sandbox runs first: imports, and each variant on the batch's first task (skills)."""
    source = str(Path(batch_path).resolve())
    warm: list[tuple[str, tuple]] = [
        ("tooltransfer.planner.apps.batch.execute:warm_up", (simulate_setting(spec, simulate),))]
    if first is not None:
        warm += [("tooltransfer.planner.apps.batch.execute:execute_job", (first.data, source, oe, ss, False))
                 for oe, ss in spec.variants.pairs()]
    return tuple(warm)


def task_jobs(spec: BatchSpec, batch_path: str | Path, t: GeneratedTask, timeout: float | None = None,
              simulate: bool | None = None, warm: tuple[tuple[str, tuple], ...] = (),
              skills: str | None = None) -> list[Job]:
    """The jobs of one task: one per variant pair (:func:`batch_jobs`); ``skills``: the digest of the
    shipped skills they plan with (:attr:`tooltransfer.planner.apps.batch.worker.Job.skills`)."""
    sim = simulate_setting(spec, simulate)
    cfg = spec.simulate
    limit = spec.timeout if timeout is None else timeout
    source = str(Path(batch_path).resolve())
    stages: tuple[Stage, ...] = ()
    if sim:
        stages = (Stage("open_loop", "tooltransfer.planner.apps.batch.execute:open_loop", (cfg.tolerance,),
                        cfg.timeout),
                  Stage("closed_loop", "tooltransfer.planner.apps.batch.execute:closed_loop",
                        (cfg.closed_loop_seed(t.index), cfg.closed_loop_tolerance, cfg.camera_noise), cfg.timeout))
    return [Job(t.task_id, f"{oe}/{ss}", args=(t.data, source, oe, ss, sim), timeout=limit, warmup=warm,
                stages=stages, skills=skills) for oe, ss in spec.variants.pairs()]


#: Tasks generated (and recorded in the store) at a time while a batch runs.
CHUNK = 64


def _lazy_jobs(spec: BatchSpec, batch_path: str | Path, store: ResultStore, first: GeneratedTask,
               timeout: float | None, simulate: bool | None,
               warm: tuple[tuple[str, tuple], ...], skills: str | None = None) -> Iterator[Job]:
    """The jobs not yet stored, task by task: tasks generated :data:`CHUNK` at a time and recorded in
    the store's ``tasks`` table before their jobs are handed out. A task that cannot be generated
    (its ranges leave no room) becomes an ``error`` row per variant, and the batch goes on."""
    from tooltransfer.planner.apps.batch.generate import GenerationError, generate_task
    from tooltransfer.planner.apps.batch.spec import dataset_folder

    dataset = str(dataset_folder(spec, batch_path))
    for lo in range(0, spec.count, CHUNK):
        chunk: list[GeneratedTask] = []
        failed: list[tuple[int, str]] = []
        for i in range(lo, min(spec.count, lo + CHUNK)):
            try:
                chunk.append(first if i == 0 else generate_task(spec, i, dataset))
            except GenerationError as exc:
                failed.append((i, str(exc)))
        store.add_tasks(task_records(chunk))
        done = store.done_for([t.task_id for t in chunk] + [f"{spec.name}-{i:05d}" for i, _ in failed])
        for t in chunk:
            yield from (j for j in task_jobs(spec, batch_path, t, timeout, simulate, warm, skills)
                        if j.key not in done)
        for i, why in failed:
            for oe, ss in spec.variants.pairs():
                job = Job(f"{spec.name}-{i:05d}", f"{oe}/{ss}", entry="builtins:dict",
                          args=({"status": "error", "reason": f"task generation: {why}"},), timeout=30)
                if job.key not in done:
                    yield job


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
    from tooltransfer.planner.apps.batch.store import SCHEMA_VERSION

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


class _Queue:
    """The jobs still to submit: drawn from an iterator as needed (a batch of a million tasks is
    generated as it runs), with a stack of jobs put back (run again first)."""

    def __init__(self, jobs: Iterable[Job]) -> None:
        self._it: Iterator[Job] = iter(jobs)
        self._back: list[Job] = []

    def peek(self) -> Job | None:
        if not self._back:
            nxt = next(self._it, None)
            if nxt is None:
                return None
            self._back.append(nxt)
        return self._back[-1]

    def pop(self) -> Job:
        job = self.peek()
        assert job is not None
        return self._back.pop()

    def append(self, job: Job) -> None:
        self._back.append(job)

    def clear(self) -> None:
        self._back.clear()
        self._it = iter(())

    def __bool__(self) -> bool:
        return self.peek() is not None


class _Dispatch:
    """The jobs of one run between the queue and the store: those waiting (``queue``), those in
    flight (future -> the job and the executor it went to) and how often each job was running when
    the pool broke (``attempts``: such a job is a suspect and runs alone)."""

    def __init__(self, todo: Iterable[Job], slots: Slots, stop: threading.Event) -> None:
        self.queue = _Queue(todo)
        self.attempts: Counter = Counter()
        self.inflight: dict[Future, tuple[Job, Any]] = {}
        self.slots, self.stop = slots, stop

    def fill(self, window: int) -> None:
        """Submit jobs until ``window`` are in flight, a suspect is running, the queue is empty or
        the run is stopping."""
        while self.queue and not self.stop.is_set() and len(self.inflight) < window:
            # a job that was running when the pool broke is a suspect: it runs alone, so a job
            # that breaks the pool again is the culprit and the others are not charged for it
            if any(self.attempts[j.key] for j, _ in self.inflight.values()):
                break
            if self.attempts[self.queue.peek().key] and self.inflight:  # type: ignore[union-attr]
                break
            job = self.queue.pop()
            try:
                self.inflight[self.slots.executor.submit(run_job, job)] = (job, self.slots.executor)
            except BrokenProcessPool:
                self.queue.append(job)
                self.slots.renew()

    def wind_down(self, console: Console, progress: bool) -> bool:
        """Stopping: cancel what has not started and forget the queue (the store can be resumed).
        Whether nothing is left running."""
        if self.queue and progress:
            console.print(f"stopping: finishing {len(self.inflight)} running jobs (Ctrl-C again to abandon "
                          "them); the store can be resumed")
        for f in [f for f in self.inflight if f.cancel()]:
            self.inflight.pop(f)
        self.queue.clear()
        return not self.inflight

    def outcome(self, f: Future, job: Job, executor: Any) -> tuple[dict[str, Any] | None, bool]:
        """The row to store for the finished future ``f`` (None: nothing to store, the job is run
        again or left for a resume) and whether the pool it ran on, the current one, broke."""
        try:
            return f.result(), False
        except CancelledError:
            if not self.stop.is_set():
                self.queue.append(job)  # cancelled by a pool replacement, never run
            return None, False
        except BrokenProcessPool:
            broke = executor is self.slots.executor  # a pool already replaced is not renewed
            self.attempts[job.key] += 1
            if self.attempts[job.key] < 2 and not self.stop.is_set():
                self.queue.append(job)
                return None, broke
            if self.stop.is_set():
                return None, broke
            return {"status": "error", "reason": "the worker process died twice while running this job",
                    "finished_at": time.time()}, broke
        except Exception as exc:  # the executor's own failure for this job (e.g. KilledWorker)
            if self.stop.is_set():
                return None, False  # not stored: run again on resume
            return {"status": "error", "reason": f"{type(exc).__name__}: {exc}", "finished_at": time.time()}, False


def _extra_fields(info: dict[tuple[str, str], dict] | Callable[[Job], dict] | None) -> Callable[[Job], dict]:
    """The extra fields of a job's row: ``info`` itself when a function, else its entry for the job's key."""
    if callable(info):
        return info
    table = info or {}
    return lambda job: table.get(job.key, {})


def _progress_bar(console: Console, progress: bool) -> Progress:
    """The run's progress bar: done of all, rate, elapsed and remaining time, counts per status."""
    return Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TaskProgressColumn(),
                    _Rate(), TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn(),
                    TextColumn("{task.fields[counts]}"), console=console, disable=not progress, transient=False)


def run_jobs(jobs: Sequence[Job] | Iterable[Job], store: ResultStore, slots: Slots, *,
             info: dict[tuple[str, str], dict] | Callable[[Job], dict] | None = None,
             progress: bool = True, console: Console | None = None, stop: threading.Event | None = None,
             catch_sigint: bool = True, total: int | None = None, skipped: int = 0) -> RunSummary:
    """Run the jobs not yet stored, storing each row as it finishes (see the module docstring).

    Args:
        jobs: a sequence (those already stored are skipped here), or an iterator of the jobs still to
            run (drawn as slots free up) with ``total`` pairs in all of which ``skipped`` are stored.
        info: extra fields per key (e.g. tool, oe, ss) added to each row, or a function of the job.
        stop: set it to stop as on Ctrl-C.
    """
    extra = _extra_fields(info)
    if isinstance(jobs, Sequence):
        done = store.done()
        todo: Iterable[Job] = [j for j in jobs if j.key not in done]
        total, skipped = len(jobs), len(jobs) - len(todo)  # type: ignore[arg-type]
    else:
        todo = jobs
        total = skipped if total is None else total
    summary = RunSummary(total=total, skipped=skipped, slots=slots.slots, kind=slots.kind)
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
    bar = _progress_bar(console, progress)
    d = _Dispatch(todo, slots, stop)
    start = time.perf_counter()

    def store_row(job: Job, row: dict[str, Any]) -> None:
        row = {**extra(job), **row, "task_id": job.task_id, "variant": job.variant}
        store.put(row)
        summary.counts[row["status"]] += 1

    try:
        with bar:
            t = bar.add_task("batch", total=total - skipped, counts="")
            while d.queue or d.inflight:
                # two jobs per slot in flight; on Dask the slots are counted again as workers join
                window = 2 * max(1, slots.current())
                summary.slots = slots.slots
                d.fill(window)
                if stop.is_set() and d.wind_down(console, progress):
                    break
                finished, _ = wait(list(d.inflight), timeout=0.25, return_when=FIRST_COMPLETED)
                broken = False
                for f in finished:
                    job, executor = d.inflight.pop(f)
                    row, broke = d.outcome(f, job, executor)
                    broken = broken or broke
                    if row is None:
                        continue
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
    """Run every (task, variant) of the batch not yet in the store ``db``, generating the tasks as it
    goes (:func:`_lazy_jobs`: the first rows are stored within seconds whatever the count).

    Before the first job: the batch's dataset is loaded and checked (a corrupt one is refused here,
    not turned into a row per job), the store is locked (:func:`tooltransfer.planner.apps.batch.store.lock_store`: a
    second ``batch run`` on it is refused), Dask workers are probed
    (:func:`tooltransfer.planner.apps.batch.dask_plugin.check_workers`), and the skills are learned and shipped to the
    executor (:mod:`tooltransfer.planner.apps.batch.shipping`; a dataset they cannot be learned from is refused before
    the store is made).

    Args:
        workers: process-pool size (default: the CPU count).
        scheduler, dask_local: run on a Dask cluster instead (see
        :func:`tooltransfer.planner.apps.batch.executors.open_executor`).
        timeout: per job [s] (default: the batch file's).
        simulate: override the batch file's ``simulate.enabled`` (part of the store's settings: a resume
            with the other setting is refused).
        resume: carry on a store that already holds rows of this batch.
        retry: statuses to run again on resume (e.g. ``("error", "timeout")``).
    """
    from tooltransfer.planner.apps.batch.executors import open_executor
    from tooltransfer.planner.apps.batch.generate import generate_task
    from tooltransfer.planner.apps.batch.spec import dataset_folder, load_batch
    from tooltransfer.planner.apps.batch.store import lock_store
    from tooltransfer.problems.dataset import load_dataset

    if timeout is not None and not timeout > 0:
        raise InputError("--timeout", "a positive number of seconds", timeout)
    spec = load_batch(batch_path)
    dataset = dataset_folder(spec, batch_path)
    load_dataset(dataset)  # a corrupt dataset is refused before the run, naming the file
    first = generate_task(spec, 0, str(dataset))
    warm = _warmup(spec, batch_path, first, simulate)
    console = console or Console(stderr=True)
    # the executor first: a scheduler that does not answer, or workers that cannot run the jobs, are refused
    # in seconds, before the skills are learned
    with lock_store(db), open_executor(workers, scheduler, dask_local) as slots:
        # learn the skills before the store exists: a dataset they fail on leaves none
        shipped = _ship_skills(slots, spec, batch_path, first, str(dataset), console, progress)
        warmed = shipped is not None
        if not warmed and not Path(db).is_file():  # not shippable: learned here for every sandbox's cache
            _warm_parent(task_jobs(spec, batch_path, first, timeout, simulate, warm), console, progress)
            warmed = True
        with ResultStore(db) as store:
            open_batch_store(store, spec, [], resume, simulate)
            if retry:
                store.forget(retry)
            return _run_store(store, slots, spec, batch_path, first, warm, warmed, timeout, simulate, progress,
                              console, shipped.digest if shipped is not None else None)


def _ship_skills(slots: Slots, spec: BatchSpec, batch_path: str | Path, first: GeneratedTask, dataset: str,
                 console: Console, progress: bool) -> ShippedSkills | None:
    """Learn the batch's skills here and ship them to the executor (:mod:`tooltransfer.planner.apps.batch.shipping`);
    the :class:`~tooltransfer.planner.apps.batch.shipping.ShippedSkills`, or None when they cannot be shipped (the
    workers then read the dataset at its path: Dask workers are probed for it)."""
    from tooltransfer.planner.apps.batch.shipping import batch_skills

    if progress:
        console.print(f"learning the skills from {dataset} ...")
    shipped = batch_skills(spec, batch_path, first)
    slots.ship(shipped, dataset)
    if progress and shipped is not None:
        console.print(f"skills {shipped.digest} ({shipped.size / 1e3:.0f} kB) shipped to the {slots.kind} workers")
    return shipped


def _run_store(store: ResultStore, slots: Slots, spec: BatchSpec, batch_path: str | Path, first: GeneratedTask,
               warm: tuple[tuple[str, tuple], ...], warmed: bool, timeout: float | None, simulate: bool | None,
               progress: bool, console: Console, skills: str | None = None) -> RunSummary:
    """:func:`run_batch` on the opened, locked and checked store and executor: the jobs not stored yet."""
    pairs = spec.variants.pairs()
    total = spec.count * len(pairs)
    skipped = store.count()
    if skipped < total and not warmed:
        _warm_parent(task_jobs(spec, batch_path, first, timeout, simulate, warm), console, progress)

    def info(job: Job) -> dict[str, Any]:
        data = job.args[0] if job.args and isinstance(job.args[0], dict) else {}
        oe, _, ss = job.variant.partition("/")
        return {"tool": data.get("tool", spec.tools[_index(job.task_id) % len(spec.tools)]), "oe": oe, "ss": ss}

    jobs = _lazy_jobs(spec, batch_path, store, first, timeout, simulate, warm, skills)
    if progress:
        ex = ", solved plans executed open and closed loop" if simulate_setting(spec, simulate) else ""
        console.print(f"batch {spec.name}: {spec.count} tasks x {len(pairs)} variants{ex} "
                      f"on a {slots.kind} ({slots.where}), results in {store.path}")
    return run_jobs(jobs, store, slots, info=info, progress=progress, console=console, total=total, skipped=skipped)


def _index(task_id: str) -> int:
    tail = task_id.rsplit("-", 1)[-1]
    return int(tail) if tail.isdigit() else 0


def _warm_parent(jobs: Sequence[Job], console: Console, progress: bool) -> None:
    """Learn the skills once here (the disk cache then serves every sandbox): one job per variant. A
    dataset the skills cannot be learned from is refused here (every job would fail on it)."""
    from tooltransfer.planner.apps.batch.execute import execute_job
    from tooltransfer.problems.dataset import DatasetError

    seen = set()
    for j in jobs:
        if j.variant in seen:
            continue
        seen.add(j.variant)
        if progress:
            console.print(f"warming up: skills and solver for {j.variant} ...")
        try:
            execute_job(*j.args[:4])
        except DatasetError:
            raise
        except InputError as exc:  # the skills (the dataset) are every job's: refused once, here
            if exc.field.startswith("skills"):
                raise
        except Exception:  # the same job will run (and report) in the batch
            pass
