"""A batch's jobs: one per task and variant pair, with the calls a new sandbox runs first and, with
simulation, the open- and closed-loop executions of each solved plan.

:func:`batch_jobs` makes every task up front; :func:`lazy_jobs` generates the tasks :data:`CHUNK` at a time as
the run (:mod:`tooltransfer.planner.apps.batch.runner`) draws the jobs, recording them in the store first, so that
a batch of a million tasks starts at once.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from tooltransfer.planner.apps.batch.generate import GeneratedTask, generate_tasks
from tooltransfer.planner.apps.batch.spec import BatchSpec
from tooltransfer.planner.apps.batch.store import ResultStore
from tooltransfer.planner.apps.batch.worker import Job, Stage

__all__ = ["CHUNK", "batch_jobs", "lazy_jobs", "simulate_setting", "task_jobs", "task_records", "warmup_calls"]


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
    up front: :func:`tooltransfer.planner.apps.batch.runner.run_batch` generates them as it runs.)"""
    tasks = list(tasks) if tasks is not None else generate_tasks(spec, batch_path)
    warm = warmup_calls(spec, batch_path, tasks[0] if tasks else None, simulate)
    return tasks, [j for t in tasks for j in task_jobs(spec, batch_path, t, timeout, simulate, warm)]


def warmup_calls(spec: BatchSpec, batch_path: str | Path, first: GeneratedTask | None,
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
              skills: str | None = None, budget: float = 1.0) -> list[Job]:
    """The jobs of one task: one per variant pair (:func:`batch_jobs`; with ``tools: choose`` each one the
    choice of a tool, :mod:`tooltransfer.planner.apps.batch.choose_job`); ``skills``: the digest of the
    shipped skills they plan with (:attr:`tooltransfer.planner.apps.batch.worker.Job.skills`); ``budget``:
    the search's and the certificate's budgets multiplied (``batch run --budget``)."""
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
    if spec.choose:  # the best of the batch's tools, executed by the choice itself (choose_job)
        return [Job(t.task_id, f"{oe}/{ss}", entry="tooltransfer.planner.apps.batch.choose_job:choose_job",
                    args=(t.data, source, oe, ss, tuple(spec.tools), cfg.closed_loop_seed(t.index), cfg.tolerance,
                          budget), timeout=limit, warmup=warm, skills=skills) for oe, ss in spec.variants.pairs()]
    return [Job(t.task_id, f"{oe}/{ss}", args=(t.data, source, oe, ss, sim, budget), timeout=limit, warmup=warm,
                stages=stages, skills=skills) for oe, ss in spec.variants.pairs()]


#: Tasks generated (and recorded in the store) at a time while a batch runs.
CHUNK = 64


def lazy_jobs(spec: BatchSpec, batch_path: str | Path, store: ResultStore, first: GeneratedTask,
               timeout: float | None, simulate: bool | None,
               warm: tuple[tuple[str, tuple], ...], skills: str | None = None, budget: float = 1.0) -> Iterator[Job]:
    """The jobs not yet stored (or stored and being run again, ``store.retrying``), task by task: tasks
    generated :data:`CHUNK` at a time and recorded in the store's ``tasks`` table before their jobs are
    handed out. A task that cannot be generated (its ranges leave no room) becomes an ``error`` row per
    variant, and the batch goes on."""
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
        done -= store.retrying  # (run again: ``batch run --retry``)
        for t in chunk:
            yield from (j for j in task_jobs(spec, batch_path, t, timeout, simulate, warm, skills, budget)
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
