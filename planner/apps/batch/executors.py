"""Where jobs run: one small protocol, :class:`Slots`, with two implementations, so the runner has one
code path (submit, wait for the first completed, store) whatever runs the jobs.

- :class:`PoolSlots` (default): a :class:`concurrent.futures.ProcessPoolExecutor` of spawned workers
  that ignore Ctrl-C and exit if the runner dies;
- :class:`tooltransfer.planner.apps.batch.dask_plugin.DaskSlots`: a Dask cluster, either a
  :class:`distributed.LocalCluster` of N worker processes with one thread each (``dask_local=N``) or
  an existing cluster (``scheduler=ADDRESS``; its workers need this package installed at the same
  version, not the dataset: the skills are shipped to them). It lives beside the Dask worker plugin,
  in the one module that imports ``distributed``, imported only when a Dask executor is asked for.

:func:`open_executor` checks the options, opens one of the two and shuts it down on exit.
:meth:`Slots.ship` puts the batch's learned skills where the jobs run
(:mod:`tooltransfer.planner.apps.batch.shipping`): a file the pool's workers read, or a worker plugin on Dask.
"""

from __future__ import annotations

import multiprocessing
import os
import tempfile
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.worker import pool_initializer

if TYPE_CHECKING:
    from tooltransfer.planner.apps.batch.shipping import ShippedSkills


class Slots(Protocol):
    """An executor and how many jobs it runs at once: what the runner
    (:func:`tooltransfer.planner.apps.batch.runner.run_jobs`) needs of the place where jobs run."""

    @property
    def executor(self) -> Executor:
        """Submit jobs here (a ``concurrent.futures`` executor); :meth:`renew` may replace it."""
        ...

    @property
    def slots(self) -> int:
        """Parallel jobs (pool workers or Dask worker threads), as last counted."""
        ...

    @property
    def kind(self) -> str:
        """What runs the jobs, for the run's summary: ``"process pool"`` or ``"dask"``."""
        ...

    @property
    def where(self) -> str:
        """Where the jobs run, in words (e.g. the number of workers and the scheduler address)."""
        ...

    def current(self) -> int:
        """Parallel jobs now (:attr:`slots`, counted again where workers can join during a run)."""
        ...

    def renew(self) -> None:
        """Replace an executor that broke (a worker process died) by a fresh one, where that is how
        it recovers; a no-op otherwise."""
        ...

    def ship(self, skills: ShippedSkills | None, dataset: str | None = None) -> None:
        """Put the batch's ``skills`` where the jobs run, before the first job; with ``skills`` None,
        check instead that the workers can read ``dataset`` at its path where that is not given.

        Raises:
            InputError: workers that cannot hold the skills or read the dataset.
        """
        ...

    def abandon(self) -> None:
        """Stop the running jobs now (a second Ctrl-C)."""
        ...


@dataclass
class PoolSlots:
    """A local process pool (:class:`Slots`): ``slots`` spawned workers, one job each.

    Attributes:
        executor: the pool; :meth:`renew` and :meth:`ship` replace it by a fresh one.
        slots: its workers.
        where: in words.
        abandoned: whether :meth:`abandon` ran (the pool is then shut down without waiting).
    """

    executor: ProcessPoolExecutor
    slots: int
    where: str
    kind: str = "process pool"
    abandoned: bool = False
    _skills: tuple[tuple[str, str], ...] = ()
    _folder: tempfile.TemporaryDirectory | None = None

    def current(self) -> int:
        """The pool's workers: their number does not change during a run."""
        return self.slots

    def renew(self) -> None:
        """Replace the broken pool by a fresh one whose workers know the shipped skills."""
        self.executor.shutdown(wait=False, cancel_futures=True)
        self.executor = _pool(self.slots, self._skills)

    def ship(self, skills: ShippedSkills | None, dataset: str | None = None) -> None:
        """Write ``skills`` once into a temporary folder (removed by :meth:`close`) and replace the
        pool, which has run no job yet, by one whose workers register the file; this process
        registers it too (jobs can run here). Nothing to do without skills: the pool's workers read
        ``dataset`` on this machine."""
        if skills is None:
            return
        from tooltransfer.atomic import write_text
        from tooltransfer.planner.apps.batch import shipping

        if self._folder is None:
            self._folder = tempfile.TemporaryDirectory(prefix="tooltransfer-skills-")
        path = write_text(os.path.join(self._folder.name, skills.file_name), skills.text)
        self._skills = (*self._skills, (skills.digest, str(path)))
        shipping.register(skills.digest, str(path))
        self.executor.shutdown(wait=True)
        self.executor = _pool(self.slots, self._skills)

    def abandon(self) -> None:
        """Terminate the pool's workers (their sandboxes exit with them) and cancel what is queued."""
        self.abandoned = True
        terminate = getattr(self.executor, "terminate_workers", None)  # Python >= 3.14
        if terminate is not None:
            terminate()
        else:
            for p in list(getattr(self.executor, "_processes", {}).values()):
                p.terminate()
        self.executor.shutdown(wait=False, cancel_futures=True)

    def close(self) -> None:
        """Shut the pool down (waiting for its workers unless abandoned), release the shipped skills
        and remove their folder."""
        self.executor.shutdown(wait=not self.abandoned, cancel_futures=True)
        if self._skills:
            from tooltransfer.planner.apps.batch import shipping

            for digest, _ in self._skills:
                shipping.release(digest)
            self._skills = ()
        if self._folder is not None:
            self._folder.cleanup()
            self._folder = None


def _pool(n: int, skills: tuple[tuple[str, str], ...] = ()) -> ProcessPoolExecutor:
    return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("spawn"),
                               initializer=pool_initializer, initargs=(skills,))


@contextmanager
def open_executor(workers: int | None = None, scheduler: str | None = None,
                  dask_local: int | None = None, dataset: str | None = None) -> Iterator[Slots]:
    """An executor for a batch (see the module docstring); shut down on exit.

    Args:
        workers: process-pool workers (default: the machine's CPUs).
        scheduler: address of a running Dask scheduler; dask_local: Dask worker processes to start
            here (at most one of the two; neither: a process pool).
        dataset: on Dask, a folder the workers must read (None when the skills are shipped to them:
            :meth:`Slots.ship`); they are probed before the first job
            (:func:`tooltransfer.planner.apps.batch.dask_plugin.check_workers`).

    Raises:
        InputError: conflicting or non-positive options; a Dask scheduler that does not answer or
            workers that cannot run the batch's jobs.
    """
    if scheduler is not None and dask_local is not None:
        raise InputError("--scheduler", "either --scheduler or --dask-local, not both", scheduler)
    for name, v in (("--workers", workers), ("--dask-local", dask_local)):
        if v is not None and v < 1:
            raise InputError(name, "a number of workers >= 1", v)
    if scheduler is None and dask_local is None:
        n = workers or os.cpu_count() or 1
        pool = PoolSlots(_pool(n), n, f"{n} local processes")
        try:
            yield pool
        finally:
            pool.close()
        return
    from tooltransfer.planner.apps.batch.dask_plugin import open_dask

    with open_dask(scheduler, dask_local, dataset) as dask:
        yield dask
