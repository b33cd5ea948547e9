"""Where jobs run: a local process pool or a Dask cluster, both as ``concurrent.futures`` executors,
so the runner has one code path (submit, wait for the first completed, store).

- process pool (default): :class:`concurrent.futures.ProcessPoolExecutor`, spawned workers that
  ignore Ctrl-C and exit if the runner dies;
- ``dask_local=N``: a :class:`distributed.LocalCluster` of N worker processes, one thread each;
- ``scheduler=ADDRESS``: an existing Dask cluster (workers need this package installed and the
  dataset at the same absolute path).

Dask clients hand out ``concurrent.futures`` futures through :meth:`distributed.Client.get_executor`.
Before the first job every Dask worker is probed (:func:`check_workers`): the package importable
there at this version, the dataset readable at its path; a worker that fails, or does not answer
within :data:`PROBE_TIMEOUT`, refuses the run naming the worker and what is missing. Connecting to
the scheduler is bounded by :data:`CONNECT_TIMEOUT` (an address where no scheduler answers is
refused with a message, not waited on).
"""

from __future__ import annotations

import logging
import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass

from dmp.errors import InputError
from planner.batch.worker import pool_initializer

#: Connecting to a Dask scheduler, waiting for its first worker, and the workers' probe [s].
CONNECT_TIMEOUT = 4.0
PROBE_TIMEOUT = 5.0

_PROBE = """
def probe(dataset, version):
    import importlib, importlib.metadata, os, socket, sys
    out = {"host": socket.gethostname(), "python": sys.version.split()[0], "problems": []}
    try:
        importlib.import_module("planner.batch.execute")
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


def check_workers(client: object, where: str, dataset: str | None = None, timeout: float = PROBE_TIMEOUT) -> None:
    """Probe every worker of a Dask ``client`` before the first job: the package importable at this
    version, ``dataset`` readable (module docstring).

    Raises:
        InputError: naming ``where`` (``--scheduler`` or ``--dask-local``), the worker and the problem.
    """
    import time

    workers = list(client.scheduler_info().get("workers", {}))  # type: ignore[attr-defined]
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
            raise InputError(f"{where} (worker {w})", "Dask workers that can run the batch's jobs (this package "
                             "installed, the dataset at the same path)", "; ".join(problems))


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
    """

    executor: Executor
    slots: int
    kind: str
    where: str
    abandoned: bool = False

    def renew(self) -> None:
        """Replace a broken process pool by a fresh one."""
        if isinstance(self.executor, ProcessPoolExecutor):
            self.executor.shutdown(wait=False, cancel_futures=True)
            self.executor = _pool(self.slots)

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


def _pool(n: int) -> ProcessPoolExecutor:
    return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("spawn"),
                               initializer=pool_initializer)


@contextmanager
def open_executor(workers: int | None = None, scheduler: str | None = None,
                  dask_local: int | None = None, dataset: str | None = None) -> Iterator[Slots]:
    """An executor for a batch (see the module docstring); shut down on exit. On Dask the workers are
    probed first (:func:`check_workers`; ``dataset``: the folder they must read)."""
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
        with client:  # type: ignore[attr-defined]
            if not client.scheduler_info().get("workers"):  # type: ignore[attr-defined]
                try:
                    client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)  # type: ignore[attr-defined]
                except Exception:
                    pass
            check_workers(client, "--scheduler" if scheduler is not None else "--dask-local", dataset)
            info = client.scheduler_info()  # type: ignore[attr-defined]
            n = sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()) or 1
            where = f"{len(info.get('workers', {}))} workers at {client.scheduler.address}"
            # retries=0: a task whose worker dies is reported (KilledWorker) and becomes an error row
            yield Slots(client.get_executor(pure=False, retries=0), n, "dask", where)
    finally:
        if cluster is not None:
            cluster.close()
