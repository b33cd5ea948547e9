"""Where jobs run: a local process pool or a Dask cluster, both as ``concurrent.futures`` executors,
so the runner has one code path (submit, wait for the first completed, store).

- process pool (default): :class:`concurrent.futures.ProcessPoolExecutor`, spawned workers that
  ignore Ctrl-C and exit if the runner dies;
- ``dask_local=N``: a :class:`distributed.LocalCluster` of N worker processes, one thread each;
- ``scheduler=ADDRESS``: an existing Dask cluster (workers need this package installed and the
  dataset at the same absolute path).

Dask clients hand out ``concurrent.futures`` futures through :meth:`distributed.Client.get_executor`.
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
                  dask_local: int | None = None) -> Iterator[Slots]:
    """An executor for a batch (see the module docstring); shut down on exit."""
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
            try:
                client = Client(scheduler, timeout=30)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError("--scheduler", "the address of a running Dask scheduler (tcp://host:8786)",
                                 f"{scheduler} ({exc})") from None
        with client:
            info = client.scheduler_info()
            n = sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()) or 1
            where = f"{len(info.get('workers', {}))} workers at {client.scheduler.address}"
            # retries=0: a task whose worker dies is reported (KilledWorker) and becomes an error row
            yield Slots(client.get_executor(pure=False, retries=0), n, "dask", where)
    finally:
        if cluster is not None:
            cluster.close()
