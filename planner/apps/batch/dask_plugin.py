"""Batch jobs on a Dask cluster: :class:`DaskSlots` (the Dask implementation of
:class:`tooltransfer.planner.apps.batch.executors.Slots`), the probe of its workers and the worker plugin
that puts the batch's skills on them. The one module of the batch that imports ``distributed``:
:func:`tooltransfer.planner.apps.batch.executors.open_executor` imports it only when Dask is asked for.

- Jobs go through :meth:`distributed.Client.get_executor`, a ``concurrent.futures`` executor.
- Before the first job every worker is probed (:func:`check_workers`): the package importable there
  at this version (and, when a dataset is given, the dataset readable at its path); a worker that
  fails, or does not answer within :data:`PROBE_TIMEOUT`, refuses the run naming the worker and what
  is missing. Connecting to a scheduler is bounded by :data:`CONNECT_TIMEOUT` (an address where no
  scheduler answers is refused with a message, not waited on).
- :class:`SkillsPlugin` is registered once per run (:meth:`DaskSlots.ship`); the scheduler keeps it
  and installs it on every worker, those that join the cluster later (dask-jobqueue's ``adapt``, a
  Kubernetes worker group scaled up) and those that restart. ``setup`` writes the skills file into the
  worker's local directory (``dask worker --local-directory``; the temporary folder if it cannot be
  written); ``teardown`` (the run unregisters the plugin when it ends, or the worker closes) removes
  it once no other run on the worker holds the same skills.
"""

from __future__ import annotations

import inspect
import logging
import tempfile
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from concurrent.futures import Executor
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import dask
from distributed import Client, LocalCluster
from distributed.diagnostics.plugin import WorkerPlugin

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.shipping import ShippedSkills, install, release

#: Connecting to a Dask scheduler, waiting for its first worker, and the workers' probe [s].
CONNECT_TIMEOUT = 4.0
PROBE_TIMEOUT = 5.0
#: How often a running batch counts the Dask workers' threads again [s] (:meth:`DaskSlots.current`).
RECOUNT = 2.0

_PROBE = """
def probe(dataset, version):
    import importlib, importlib.metadata, os, socket, sys
    out = {"host": socket.gethostname(), "python": sys.version.split()[0], "problems": []}
    try:
        importlib.import_module("tooltransfer.planner.apps.batch.execute")
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


def _probe_function() -> Callable[[str | None, str | None], dict[str, Any]]:
    """The probe, made from source: cloudpickle ships it by value, so a worker without this package
    can run it and say so."""
    ns: dict[str, Any] = {"__name__": "tooltransfer_worker_probe"}
    exec(_PROBE, ns)
    return ns["probe"]  # type: ignore[no-any-return]


def _version() -> str | None:
    import importlib.metadata

    try:
        return importlib.metadata.version("tooltransfer")
    except importlib.metadata.PackageNotFoundError:
        return None


def workers_info(client: Client) -> dict[str, dict[str, Any]]:
    """Every worker the scheduler knows (address -> its info, with ``nthreads``). Asks for all of them
    (``n_workers=-1``) where :meth:`~distributed.Client.scheduler_info` takes that argument: those
    releases of distributed list only the first five workers by default."""
    info = client.scheduler_info
    try:
        every = "n_workers" in inspect.signature(info).parameters
    except (TypeError, ValueError):
        every = False
    answer: dict[str, Any] = info(n_workers=-1) if every else info()  # type: ignore[call-arg]
    return dict(answer.get("workers", {}))


def check_workers(client: Client, where: str, dataset: str | None = None, timeout: float = PROBE_TIMEOUT) -> None:
    """Probe every worker of a Dask ``client`` before the first job: the package importable at this
    version, ``dataset`` readable (module docstring); ``timeout`` [s] for all the answers.

    Raises:
        InputError: naming ``where`` (``--scheduler`` or ``--dask-local``), the worker and the problem.
    """
    workers = list(workers_info(client))
    if not workers:
        raise InputError(where, "a Dask cluster with at least one worker", "no worker connected")
    probe, token = _probe_function(), uuid.uuid4().hex[:12]
    futures = {w: client.submit(probe, dataset, _version(), workers=[w], allow_other_workers=False,
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


def _connect(scheduler: str, timeout: float = CONNECT_TIMEOUT) -> Client:
    """A :class:`distributed.Client` of the scheduler at ``scheduler``, within ``timeout`` [s] in all."""
    box: dict[str, Any] = {}

    def connect() -> None:
        try:
            box["client"] = Client(scheduler, timeout=timeout)
        except BaseException as exc:
            box["error"] = exc

    th = threading.Thread(target=connect, daemon=True, name="dask-connect")
    th.start()
    th.join(timeout + 1.0)
    if "client" in box:
        client: Client = box["client"]
        return client
    why = (f"no Dask scheduler answered within {timeout:g} s" if th.is_alive() else
           f"{type(box.get('error')).__name__}: {box.get('error')}")
    raise InputError("--scheduler", "the address of a running Dask scheduler (tcp://host:8786)",
                     f"{scheduler} ({why})")


class SkillsPlugin(WorkerPlugin):
    """Installs ``skills`` on each worker it is set up on (module docstring)."""

    def __init__(self, skills: ShippedSkills) -> None:
        self.skills = skills

    def setup(self, worker: Any) -> None:
        try:
            install(self.skills, worker.local_directory)
        except OSError:  # a local directory it cannot write: the machine's temporary folder
            install(self.skills, tempfile.gettempdir())

    def teardown(self, worker: Any) -> None:
        release(self.skills.digest)


@dataclass
class DaskSlots:
    """A Dask cluster (:class:`tooltransfer.planner.apps.batch.executors.Slots`): one job per worker thread.

    Attributes:
        executor: the client's executor (no retries: a task whose worker dies is reported,
            ``KilledWorker``, and becomes an error row).
        slots: the workers' threads, as last counted (:meth:`current`).
        where: the number of workers and the scheduler's address.
        client: the Dask client.
        flag: the option that chose the cluster (``--scheduler``, ``--dask-local``), named in messages.
    """

    executor: Executor
    slots: int
    where: str
    client: Client
    flag: str
    kind: str = "dask"
    _plugins: list[str] = field(default_factory=list)
    _counted: float = 0.0

    def current(self) -> int:
        """The threads of the workers connected, counted again every :data:`RECOUNT` seconds, so
        workers that join after the start (dask-jobqueue's ``adapt``, SLURM jobs that leave the queue
        later, a scaled-up worker group) get jobs too; a cluster that shrinks keeps the largest count
        (the scheduler queues what it cannot place)."""
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
        """Nothing to replace: a worker that dies fails its own task, the executor goes on."""

    def ship(self, skills: ShippedSkills | None, dataset: str | None = None) -> None:
        """Register a :class:`SkillsPlugin` that writes ``skills`` into each worker's local directory,
        on the workers there and on those that join later (unregistered by :meth:`close`). With no
        skills to ship (``skills`` None) the workers are probed for ``dataset`` at its path instead.

        Raises:
            InputError: a worker that cannot install them, or (without skills) cannot read ``dataset``.
        """
        if skills is None:
            if dataset:
                check_workers(self.client, self.flag, dataset)
            return
        name = f"tooltransfer-skills-{skills.digest}-{uuid.uuid4().hex[:8]}"
        try:
            self.client.register_plugin(SkillsPlugin(skills), name=name)
        except Exception as exc:
            raise InputError(self.flag, "Dask workers that can hold the batch's skills (a file in their local "
                             "directory)", f"{type(exc).__name__}: {exc}") from None
        self._plugins.append(name)

    def abandon(self) -> None:
        """Nothing to do here: the cluster's jobs are cancelled when the client closes."""

    def close(self) -> None:
        """Unregister the skills plugins (their teardown removes the workers' files)."""
        for name in self._plugins:
            try:
                self.client.unregister_worker_plugin(name)
            except Exception:  # a worker gone or the scheduler closing: its local directory goes with it
                pass
        self._plugins.clear()


@contextmanager
def open_dask(scheduler: str | None, dask_local: int | None, dataset: str | None = None) -> Iterator[DaskSlots]:
    """The cluster at the address ``scheduler``, or a local one of ``dask_local`` worker processes
    with one thread each, its workers probed (:func:`check_workers`, ``dataset`` as there); the
    client (and a local cluster) closed on exit.

    Raises:
        InputError: no scheduler answering at ``scheduler``; workers that cannot run the jobs.
    """
    cluster = None
    try:
        if dask_local is not None:
            # the workers only wait on their sandboxes: their statistical profiler (100 Hz) and GIL
            # monitor (1 kHz) would take CPU from the jobs
            with dask.config.set({"distributed.worker.profile.enabled": False,
                                  "distributed.admin.system-monitor.gil.enabled": False}):
                cluster = LocalCluster(n_workers=dask_local, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
        elif scheduler is not None:
            client = _connect(scheduler)
        else:
            raise InputError("--scheduler", "a scheduler address or a number of local Dask workers", None)
        flag = "--scheduler" if scheduler is not None else "--dask-local"
        with client:
            if not workers_info(client):
                try:
                    client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)
                except Exception:
                    pass
            check_workers(client, flag, dataset)
            info = workers_info(client)
            n = sum(w.get("nthreads", 1) for w in info.values()) or 1
            where = f"{len(info)} workers at {client.scheduler.address}"
            slots = DaskSlots(client.get_executor(pure=False, retries=0), n, where, client, flag)
            try:
                yield slots
            finally:
                slots.close()
    finally:
        if cluster is not None:
            cluster.close()
