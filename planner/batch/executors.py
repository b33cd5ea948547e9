"""Where jobs run: a local process pool or a Dask cluster, both as ``concurrent.futures`` executors,
so the runner has one code path (submit, wait for the first completed, store).

- process pool (default): :class:`concurrent.futures.ProcessPoolExecutor`, spawned workers that
  ignore Ctrl-C and exit if the runner dies;
- ``dask_local=N``: a :class:`distributed.LocalCluster` of N worker processes, one thread each;
- ``scheduler=ADDRESS``: an existing Dask cluster (workers need this package installed, at the same
  version; not the dataset: the skills are shipped to them).

Dask clients hand out ``concurrent.futures`` futures through :meth:`distributed.Client.get_executor`.
Before the first job every Dask worker is probed (:func:`check_workers`): the package importable
there at this version (and, when a dataset is given, the dataset readable at its path); a worker
that fails, or does not answer within :data:`PROBE_TIMEOUT`, refuses the run naming the worker and
what is missing. Connecting to the scheduler is bounded by :data:`CONNECT_TIMEOUT` (an address where
no scheduler answers is refused with a message, not waited on). :meth:`Slots.ship` then puts the
batch's learned skills where the jobs run (:mod:`tooltransfer.planner.batch.shipping`): a file the pool's workers
read, or a worker plugin on Dask.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from tooltransfer.errors import InputError
from tooltransfer.planner.batch.worker import pool_initializer

if TYPE_CHECKING:
    from tooltransfer.planner.batch.shipping import ShippedSkills

#: Connecting to a Dask scheduler, waiting for its first worker, and the workers' probe [s].
CONNECT_TIMEOUT = 4.0
PROBE_TIMEOUT = 5.0
#: How often a running batch counts the Dask workers' threads again [s] (:meth:`Slots.current`).
RECOUNT = 2.0

_PROBE = """
def probe(dataset, version):
    import importlib, importlib.metadata, os, socket, sys
    out = {"host": socket.gethostname(), "python": sys.version.split()[0], "problems": []}
    try:
        importlib.import_module("tooltransfer.planner.batch.execute")
    except Exception as exc:
        out["problems"].append(f"the tooltransfer package cannot be imported ({type(exc).__name__}: {exc})")
    try:
        found = importlib.metadata.version("tooltransfer")
    except Exception:
        found = None
    if version and found and found != version:
        out["problems"].append(f"tooltransfer {found} installed, not {version} as here")
    if dataset and not os.path.isfile(os.path.join(dataset, "meta.yaml")):
        out["problems"].append(f"no dataset at {dataset} (its meta.yaml is not readable there)")
    return out
"""


def _probe_function():  # made from source: cloudpickle ships it by value, no package needed there
    ns: dict = {"__name__": "tooltransfer_worker_probe"}
    exec(_PROBE, ns)
    return ns["probe"]


def _version() -> str | None:
    import importlib.metadata

    try:
        return importlib.metadata.version("tooltransfer")
    except importlib.metadata.PackageNotFoundError:
        return None


def workers_info(client: object) -> dict[str, dict]:
    """Every worker the scheduler knows (address -> its info, with ``nthreads``): all of them, also on
    the distributed releases (2025 to mid-2026) whose :meth:`~distributed.Client.scheduler_info` lists
    only the first five by default (the probe and the slot count saw five workers of a larger cluster)."""
    import inspect

    info = client.scheduler_info  # type: ignore[attr-defined]
    try:
        every = "n_workers" in inspect.signature(info).parameters
    except (TypeError, ValueError):
        every = False
    return dict((info(n_workers=-1) if every else info()).get("workers", {}))


def check_workers(client: object, where: str, dataset: str | None = None, timeout: float = PROBE_TIMEOUT) -> None:
    """Probe every worker of a Dask ``client`` before the first job: the package importable at this
    version, ``dataset`` readable (module docstring).

    Raises:
        InputError: naming ``where`` (``--scheduler`` or ``--dask-local``), the worker and the problem.
    """
    workers = list(workers_info(client))
    if not workers:
        raise InputError(where, "a Dask cluster with at least one worker", "no worker connected")
    import uuid

    probe, token = _probe_function(), uuid.uuid4().hex[:12]
    futures = {w: client.submit(probe, dataset, _version(), workers=[w], allow_other_workers=False,  # type: ignore[attr-defined]
                                pure=False, key=f"tooltransfer-probe-{token}-{i}") for i, w in enumerate(workers)}
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and any(f.status == "pending" for f in futures.values()):
        time.sleep(0.02)
    answers: dict[str, object] = {}
    for w, f in futures.items():
        if f.status == "finished":
            answers[w] = f.result()
        elif f.status == "error":
            answers[w] = f.exception()
    for f in futures.values():
        f.cancel()
    silent = [w for w in futures if w not in answers]
    if silent:
        raise InputError(where, f"Dask workers that answer within {timeout:g} s", f"no answer from {', '.join(silent)}")
    for w, a in answers.items():
        if isinstance(a, BaseException):
            raise InputError(f"{where} (worker {w})", "Dask workers that can run the batch's jobs", str(a))
        problems = a.get("problems", []) if isinstance(a, dict) else [f"an answer of {type(a).__name__}"]
        if problems:
            need = "this package installed, the dataset at the same path" if dataset else "this package installed"
            raise InputError(f"{where} (worker {w})", f"Dask workers that can run the batch's jobs ({need})",
                             "; ".join(problems))


def _connect(scheduler: str, timeout: float = CONNECT_TIMEOUT) -> object:
    """A :class:`distributed.Client` of the scheduler at ``scheduler``, within ``timeout`` [s] in all."""
    import threading

    from distributed import Client

    box: dict = {}

    def connect() -> None:
        try:
            box["client"] = Client(scheduler, timeout=timeout)
        except BaseException as exc:
            box["error"] = exc

    th = threading.Thread(target=connect, daemon=True, name="dask-connect")
    th.start()
    th.join(timeout + 1.0)
    if "client" in box:
        return box["client"]
    why = (f"no Dask scheduler answered within {timeout:g} s" if th.is_alive() else
           f"{type(box.get('error')).__name__}: {box.get('error')}")
    raise InputError("--scheduler", "the address of a running Dask scheduler (tcp://host:8786)",
                     f"{scheduler} ({why})")


@dataclass
class Slots:
    """An executor and how many jobs it runs at once.

    Attributes:
        executor: submit jobs here.
        slots: parallel jobs (pool workers or Dask worker threads).
        kind: ``"process pool"`` or ``"dask"``.
        where: in words (e.g. the scheduler address).
        client: the Dask client (None for the pool); flag: the option that chose it (``--scheduler``,
            ``--dask-local``), named in messages.
    """

    executor: Executor
    slots: int
    kind: str
    where: str
    abandoned: bool = False
    client: object | None = None
    flag: str = ""
    _skills: tuple[tuple[str, str], ...] = ()
    _plugins: list[str] = field(default_factory=list)
    _folder: tempfile.TemporaryDirectory | None = None
    _counted: float = 0.0

    def current(self) -> int:
        """Parallel jobs now: on Dask the threads of the workers connected, counted again every
        :data:`RECOUNT` seconds, so workers that join after the start (dask-jobqueue's ``adapt``, SLURM
        jobs that leave the queue later, a scaled-up worker group) get jobs too; a cluster that shrinks
        keeps the largest count (the scheduler queues what it cannot place)."""
        if self.client is None:
            return self.slots
        now = time.monotonic()
        if now - self._counted >= RECOUNT:
            self._counted = now
            try:
                n = sum(w.get("nthreads", 1) for w in workers_info(self.client).values())
            except Exception:  # the scheduler busy or gone: the futures will say so
                n = 0
            self.slots = max(self.slots, n)
        return self.slots

    def renew(self) -> None:
        """Replace a broken process pool by a fresh one."""
        if isinstance(self.executor, ProcessPoolExecutor):
            self.executor.shutdown(wait=False, cancel_futures=True)
            self.executor = _pool(self.slots, self._skills)

    def ship(self, skills: ShippedSkills | None, dataset: str | None = None) -> None:
        """Put the batch's skills where the jobs run, before the first job (:mod:`tooltransfer.planner.batch.shipping`):
        on the pool, one file in a temporary folder (removed when the executor closes) that every pool
        worker registers; on Dask, a worker plugin that writes it into each worker's local directory,
        now and on workers that join later (unregistered when the executor closes). With no skills to
        ship (``skills`` None) Dask workers are probed for ``dataset`` at its path instead.

        Raises:
            InputError: a Dask worker that cannot install them, or (without skills) cannot read ``dataset``.
        """
        if skills is None:
            if self.client is not None and dataset:
                check_workers(self.client, self.flag, dataset)
            return
        if self.client is None:
            from tooltransfer.atomic import write_text

            if self._folder is None:
                self._folder = tempfile.TemporaryDirectory(prefix="tooltransfer-skills-")
            path = write_text(os.path.join(self._folder.name, skills.file_name), skills.text)
            self._skills = (*self._skills, (skills.digest, str(path)))
            from tooltransfer.planner.batch import shipping

            shipping.register(skills.digest, str(path))  # jobs run here too (run_job called in this process)
            if isinstance(self.executor, ProcessPoolExecutor):  # no job submitted yet: a pool that knows them
                self.executor.shutdown(wait=True)
                self.executor = _pool(self.slots, self._skills)
            return
        import uuid

        from tooltransfer.planner.batch.dask_plugin import SkillsPlugin

        name = f"tooltransfer-skills-{skills.digest}-{uuid.uuid4().hex[:8]}"
        try:
            self.client.register_plugin(SkillsPlugin(skills), name=name)  # type: ignore[attr-defined]
        except Exception as exc:
            raise InputError(self.flag, "Dask workers that can hold the batch's skills (a file in their local "
                             "directory)", f"{type(exc).__name__}: {exc}") from None
        self._plugins.append(name)

    def close_shipping(self) -> None:
        """Undo :meth:`ship`: unregister the Dask plugins (their teardown removes the workers' files),
        remove the pool's temporary folder."""
        for name in self._plugins:
            try:
                self.client.unregister_worker_plugin(name)  # type: ignore[attr-defined]
            except Exception:  # a worker gone or the scheduler closing: its local directory goes with it
                pass
        self._plugins.clear()
        if self._skills:
            from tooltransfer.planner.batch import shipping

            for digest, _ in self._skills:
                shipping.release(digest)
            self._skills = ()
        if self._folder is not None:
            self._folder.cleanup()
            self._folder = None

    def abandon(self) -> None:
        """Stop the running jobs now (a second Ctrl-C): terminate the pool's workers (their sandboxes
        exit with them); a Dask cluster's jobs are cancelled when the client closes."""
        self.abandoned = True
        if isinstance(self.executor, ProcessPoolExecutor):
            terminate = getattr(self.executor, "terminate_workers", None)  # Python >= 3.14
            if terminate is not None:
                terminate()
            else:
                for p in list(getattr(self.executor, "_processes", {}).values()):
                    p.terminate()
            self.executor.shutdown(wait=False, cancel_futures=True)


def _pool(n: int, skills: tuple[tuple[str, str], ...] = ()) -> ProcessPoolExecutor:
    return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("spawn"),
                               initializer=pool_initializer, initargs=(skills,))


@contextmanager
def open_executor(workers: int | None = None, scheduler: str | None = None,
                  dask_local: int | None = None, dataset: str | None = None) -> Iterator[Slots]:
    """An executor for a batch (see the module docstring); shut down on exit. On Dask the workers are
    probed first (:func:`check_workers`; ``dataset``: a folder they must read, None when the skills are
    shipped to them: :meth:`Slots.ship`)."""
    if scheduler is not None and dask_local is not None:
        raise InputError("--scheduler", "either --scheduler or --dask-local, not both", scheduler)
    for name, v in (("--workers", workers), ("--dask-local", dask_local)):
        if v is not None and v < 1:
            raise InputError(name, "a number of workers >= 1", v)
    if scheduler is None and dask_local is None:
        n = workers or os.cpu_count() or 1
        slots = Slots(_pool(n), n, "process pool", f"{n} local processes")
        try:
            yield slots
        finally:
            slots.executor.shutdown(wait=not slots.abandoned, cancel_futures=True)
            slots.close_shipping()
        return
    from distributed import Client, LocalCluster

    cluster = None
    try:
        if dask_local is not None:
            import dask

            # the workers only wait on their sandboxes: their statistical profiler (100 Hz) and GIL
            # monitor (1 kHz) would take CPU from the jobs
            with dask.config.set({"distributed.worker.profile.enabled": False,
                                  "distributed.admin.system-monitor.gil.enabled": False}):
                cluster = LocalCluster(n_workers=dask_local, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
        else:
            client = _connect(scheduler)  # type: ignore[arg-type]
        flag = "--scheduler" if scheduler is not None else "--dask-local"
        with client:  # type: ignore[attr-defined]
            if not workers_info(client):
                try:
                    client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)  # type: ignore[attr-defined]
                except Exception:
                    pass
            check_workers(client, flag, dataset)
            info = workers_info(client)
            n = sum(w.get("nthreads", 1) for w in info.values()) or 1
            where = f"{len(info)} workers at {client.scheduler.address}"
            # retries=0: a task whose worker dies is reported (KilledWorker) and becomes an error row
            slots = Slots(client.get_executor(pure=False, retries=0), n, "dask", where, client=client, flag=flag)
            try:
                yield slots
            finally:
                slots.close_shipping()
    finally:
        if cluster is not None:
            cluster.close()
