"""Running a batch: jobs to an executor, rows to the store as each job finishes, progress, Ctrl-C.

One code path for the process pool and Dask (:mod:`tooltransfer.planner.apps.batch.executors`): at most two jobs per
slot are in flight; each finished future's row is committed at once. ``resume`` skips the
(task, variant) pairs already stored; without it a store that already holds rows is refused. The
first Ctrl-C (SIGINT) stops submitting, cancels what has not started, waits for the running jobs
at most their timeout plus :data:`STOP_GRACE` and stores them, then abandons what is left; a second
Ctrl-C abandons them at once. A store that cannot take a row (a full disk, a damaged page) stops the
run at once with :class:`~tooltransfer.planner.apps.batch.store_file.StoreError` (the rows stored
before are kept). Either way the
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

import signal
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
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
from tooltransfer.planner.apps.batch.generate import GeneratedTask
from tooltransfer.planner.apps.batch.jobs import lazy_jobs, simulate_setting, task_jobs, warmup_calls
from tooltransfer.planner.apps.batch.spec import BatchSpec
from tooltransfer.planner.apps.batch.store import STATUSES, ResultStore
from tooltransfer.planner.apps.batch.store_file import StoreError
from tooltransfer.planner.apps.batch.store_settings import open_batch_store
from tooltransfer.planner.apps.batch.worker import Job, run_job

if TYPE_CHECKING:
    from tooltransfer.planner.apps.batch.shipping import ShippedSkills

STOP_GRACE = 5.0
"""After the first Ctrl-C, the running jobs get their timeout plus this long [s] to finish and be stored;
those still running then (a job queued on a worker behind another, a job in an execution stage) are
abandoned and run again on ``--resume``."""

@dataclass
class RunSummary:
    """What a run did.

    Attributes:
        total: (task, variant) pairs in the batch.
        skipped: pairs already in the store (resume).
        counts: rows stored by this run, per status.
        kept: of those, rows run again that gave no verdict where the store had one, which it kept.
        interrupted: stopped by Ctrl-C before the end.
        wall: wall time of the run [s] (after the warm-up).
        slots: parallel jobs.
        kind: executor kind.
    """

    total: int
    skipped: int
    counts: Counter = field(default_factory=Counter)
    kept: int = 0
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
                with _sigint_held():  # a pool worker started here ignores Ctrl-C from its first instruction
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


@contextmanager
def _sigint_held() -> Iterator[None]:
    """Hold SIGINT (blocked, delivered when the block ends) around a submit that may start pool workers:
    a process started meanwhile inherits the block, so a Ctrl-C while it boots (before its initializer
    ignores SIGINT) cannot kill it with a traceback; the runner's own Ctrl-C is only delayed."""
    held = hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread()
    if held:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        if held:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


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
        done = store.done() - store.retrying
        todo: Iterable[Job] = [j for j in jobs if j.key not in done]
        total, skipped = len(jobs), len(jobs) - len(todo)  # type: ignore[arg-type]
    else:
        todo = jobs
        total = skipped if total is None else total
    summary = RunSummary(total=total, skipped=skipped, slots=slots.slots, kind=slots.kind)
    stop = stop or threading.Event()
    aborted = False
    stop_by: float | None = None  # once stopping: when the jobs still running are abandoned
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
        summary.kept += not store.put(row)
        summary.counts[row["status"]] += 1

    try:
        with bar:
            t = bar.add_task("batch", total=total - skipped, counts="")
            while d.queue or d.inflight:
                # two jobs per slot in flight; on Dask the slots are counted again as workers join
                window = 2 * max(1, slots.current())
                summary.slots = slots.slots
                d.fill(window)
                if stop.is_set():
                    if stop_by is None:
                        stop_by = time.monotonic() + STOP_GRACE + max(
                            (j.timeout for j, _ in d.inflight.values()), default=0.0)
                    if d.wind_down(console, progress):
                        break
                    if time.monotonic() > stop_by:  # a job queued behind a running one, a stage: not waited for
                        if progress:
                            console.print(f"stopping: abandoning {len(d.inflight)} jobs still running after the "
                                          "per-job timeout (they run again on --resume)")
                        slots.abandon()
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
    except StoreError:  # the store cannot take more rows (a full disk, a damaged page): stop now
        slots.abandon()
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    summary.wall = time.perf_counter() - start
    summary.interrupted = aborted or stop.is_set()
    return summary


def run_batch(batch_path: str | Path, db: str | Path, *, workers: int | None = None, scheduler: str | None = None,
              dask_local: int | None = None, timeout: float | None = None, simulate: bool | None = None,
              resume: bool = False, retry: Sequence[str] = (), progress: bool = True,
              console: Console | None = None, budget: float = 1.0) -> RunSummary:
    """Run every (task, variant) of the batch not yet in the store ``db``, generating the tasks as it
    goes (:func:`tooltransfer.planner.apps.batch.jobs.lazy_jobs`: the first rows are stored within seconds
    whatever the count).

    Before the first job: a store another run writes, or one with results without ``resume``, is refused
    at once (:func:`refuse_taken_store`); the batch's dataset is loaded and checked (a corrupt one is refused here,
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
        retry: statuses to run again on resume (e.g. ``("error", "timeout")``); each row stays until its new
            result replaces it, and one that gave no verdict keeps a stored verdict (``ResultStore.put``).
        budget: the search's and the certificate's budgets multiplied (>= 1; with ``retry=("unknown",)``
            the undecided tasks get more: :func:`~tooltransfer.planner.planning.solve.solve`).
    """
    from tooltransfer.planner.apps.batch.executors import open_executor
    from tooltransfer.planner.apps.batch.generate import generate_task
    from tooltransfer.planner.apps.batch.spec import dataset_folder, load_batch
    from tooltransfer.planner.apps.batch.store import lock_store
    from tooltransfer.planner.planning.solve import check_budget
    from tooltransfer.problems.dataset import load_dataset

    if timeout is not None and not timeout > 0:
        raise InputError("--timeout", "a positive number of seconds", timeout)
    check_budget(budget, "--budget")
    spec = load_batch(batch_path)
    refuse_taken_store(db, resume)  # at once: before the dataset is read and the skills are learned
    dataset = dataset_folder(spec, batch_path)
    load_dataset(dataset)  # a corrupt dataset is refused before the run, naming the file
    first = generate_task(spec, 0, str(dataset))
    warm = warmup_calls(spec, batch_path, first, simulate)
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
                store.again(retry)
            return _run_store(store, slots, spec, batch_path, first, warm, warmed, timeout, simulate, progress,
                              console, shipped.digest if shipped is not None else None, budget)


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
               progress: bool, console: Console, skills: str | None = None, budget: float = 1.0) -> RunSummary:
    """:func:`run_batch` on the opened, locked and checked store and executor: the jobs not stored yet."""
    pairs = spec.variants.pairs()
    total = spec.count * len(pairs)
    skipped = store.count() - len(store.retrying)
    if skipped < total and not warmed:
        _warm_parent(task_jobs(spec, batch_path, first, timeout, simulate, warm), console, progress)

    def info(job: Job) -> dict[str, Any]:
        data = job.args[0] if job.args and isinstance(job.args[0], dict) else {}
        oe, _, ss = job.variant.partition("/")
        return {"tool": data.get("tool", spec.tools[_index(job.task_id) % len(spec.tools)]), "oe": oe, "ss": ss}

    jobs = lazy_jobs(spec, batch_path, store, first, timeout, simulate, warm, skills, budget)
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


def refuse_taken_store(db: str | Path, resume: bool) -> None:
    """Refuse at once, before the dataset is read and the skills are learned (about 10 s where they are not
    cached), the store ``db`` when another ``batch run`` writes it (its lock,
    :func:`tooltransfer.planner.apps.batch.store.lock_store`, is taken and let go; the run takes it again
    before it opens the store) or, without ``resume``, when it already holds results: the refusal
    :func:`tooltransfer.planner.apps.batch.store_settings.open_batch_store` makes, read here without writing
    to the file. All else about the store (another batch's, another schema, not a store at all) is left to
    ``open_batch_store``.

    Raises:
        InputError: naming ``--db`` (in use, and by whom) or ``--resume`` (how many results it holds).
    """
    import sqlite3
    from contextlib import closing

    from tooltransfer.planner.apps.batch.store import lock_store

    path = Path(db)
    if path.with_name(path.name + ".lock").is_file():  # a run holding it has made it
        with lock_store(path):
            pass
    if resume or not path.is_file():
        return
    try:
        with closing(sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)) as con:
            (n,) = con.execute("SELECT COUNT(*) FROM results").fetchone()
    except sqlite3.Error:  # not a store, or unreadable: open_batch_store says what it is
        return
    if n:
        raise InputError("--resume", f"--resume to carry on ({path} already holds {n} results) or a new --db",
                         "neither")
