"""Execution benchmark: how close the planner's plans bring the puck to the target on the simulated Omni.

Run with `python benchmarks/bench_execution.py` (or `make bench-exec`). For every task:

1. plan it (:func:`tooltransfer.planner.planning.solve.solve`): status, reason, planning wall and CPU time;
2. a solved plan is executed open loop (:func:`tooltransfer.planner.execution.simulate.simulate_plan`) and closed loop
   (:func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`, a fixed camera-noise seed): the puck's final
   distance to the target [m], the closed loop's status, re-plans (count and wall times) and
   re-contacts. An exception in either (or in the planner) is recorded as
   ``"exception: <type>: <message>"`` and counted; the benchmark goes on;
3. the model prediction error: the tool poses MuJoCo executed open loop (its recorded track)
   replayed through the push model (:func:`tooltransfer.tools.pushing.forward.simulate`, the plan's
   ``mechanics_mu``, ``mechanics_c``) from the start, the predicted final puck against the recorded
   one (the recording's object track is the true pose) [m]; with the plan's self-consistency and
   planned re-contacts;
4. unless ``--no-mismatch``, the plan on mismatched plants (:data:`MISMATCH_PLANTS`), open and closed
   loop: MuJoCo with tool friction 0.5 and table friction 0.2, and the quasi-static
   :class:`tooltransfer.planner.execution.plant.ModelPlant` with mu and c 0.6 and 1.4 times the plan's (camera noise
   1.5 mm; open loop there is the push model run on the plan's tool poses);
5. with ``--faults NAMES`` (comma-separated, or ``all``), the closed loop on the fault plants of
   :data:`tooltransfer.planner.execution.fault_plants.FAULTS` (a frozen camera, dropped, outlier and
   noisy frames, a tracking offset and lag, driver faults, bumps) over the MuJoCo platform
   (``--fault-base sim``, default) or the push model (``model``): statuses, final errors, the
   commands overlapping an obstacle or leaving the reach, exceptions, the time a frozen camera took
   to end the run and whether the tool ended clear of the object (:mod:`fault_runs`).

Tasks: the generated batch ``problems/batch/execution_60.yaml`` (60 tasks, five library tools in
turn, up to one obstacle) and the paper's tasks ``problems/paper/transfer_tool2.yaml`` and
``demo_tool1.yaml`` (reported apart). Every task runs with every variant of ``--variants``
(``oe/ss`` pairs; default the planner's default ``qp/opt``). Tasks run in a process pool
(``--workers``, default 2); each worker learns (or loads) the skills once, before its first task.

Report: the plans' push mechanics, the solve rate with the infeasible reasons grouped, the open- and
closed-loop final errors over solved plans (median, p90, max, share within 2 mm and 5 mm; the shares
count every solved plan, an execution that raised counts as a miss), the model prediction error
(median, p90, max) and the largest self-consistency, the closed loop's statuses and re-plan times
(median, p90, max over every re-plan), a table of the plants (nominal and mismatched: within 3 mm
open and closed loop, closed-loop median, statuses) with the targets (closed loop nominal
>= 95 % within 2 mm without exception, mismatched >= 90 % within 3 mm, re-plan median <= 30 ms), a
per-tool table, the paper tasks, the slowest tasks and the total time. ``--json PATH`` writes every
per-task row (and the run's settings) for comparing runs.

    python benchmarks/bench_execution.py                                  # 60 + 2 tasks, qp/opt
    python benchmarks/bench_execution.py --count 10 --no-closed-loop --no-mismatch  # a quick look
    python benchmarks/bench_execution.py --variants qp/opt,mapping/opt --json out/exec.json
    python benchmarks/bench_execution.py --count 6 --no-mismatch --faults all   # the fault plants

Single-threaded BLAS (``OPENBLAS_NUM_THREADS=1``); planning times vary by some percent on a shared
machine. Learned skills are cached in ``$TOOLTRANSFER_CACHE`` (default ``~/.cache/tooltransfer``),
keyed by the dataset's content, not by the code: point it at an empty folder to learn them afresh.

Adding a measure: compute it in :func:`run_task` (a new key of the row; it goes to the JSON as is)
and show it in :func:`report`.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import math
import multiprocessing
import re
import signal
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from fault_runs import FAULT_BASES, fault_table, parse_faults, run_faults

from tooltransfer.planner.apps.batch.execute import finite_or_none
from tooltransfer.planner.planning import variant_registry

ROOT = Path(__file__).resolve().parents[1]
BATCH = ROOT / "problems" / "batch" / "execution_60.yaml"
PAPER = (ROOT / "problems" / "paper" / "transfer_tool2.yaml", ROOT / "problems" / "paper" / "demo_tool1.yaml")
OE_VARIANTS: tuple[str, ...] = tuple(variant_registry.OE_VARIANTS)
SS_VARIANTS: tuple[str, ...] = tuple(variant_registry.SS_VARIANTS)
WITHIN = (0.002, 0.005)
"""Final-error thresholds [m] of the shares reported."""

Row = dict[str, Any]


@dataclass(frozen=True)
class Job:
    """One task with one variant, as sent to a worker.

    Attributes:
        task_id: the generated task's id or the paper task's name.
        kind: ``"generated"`` or ``"paper"``.
        tool: library tool name.
        index: position in the batch (-1 for paper tasks).
        n_obstacles: obstacles in the task.
        data: the task's fields (as in a task file).
        source: the path relative paths in ``data`` are relative to.
        oe, ss: the variant.
        closed_loop: also execute closed loop.
        mismatch: also execute on the mismatched plants (:data:`MISMATCH_PLANTS`).
        seed: camera-noise seed of the closed loop.
        timeout: [s] per stage (planning, open loop, closed loop); 0 for none.
        faults: names of the fault plants to run the closed loop on (:mod:`fault_runs`);
        fault_base: ``"sim"`` or ``"model"``, the plant they wrap.
    """

    task_id: str
    kind: str
    tool: str
    index: int
    n_obstacles: int
    data: dict[str, Any] = field(repr=False)
    source: str
    oe: str
    ss: str
    closed_loop: bool = True
    mismatch: bool = True
    seed: int = 0
    timeout: float = 0.0
    faults: tuple[str, ...] = ()
    fault_base: str = "sim"

    @property
    def variant(self) -> str:
        return f"{self.oe}/{self.ss}"


class StageTimeout(Exception):
    """A stage of a task ran past ``--timeout``."""


@contextmanager
def _deadline(seconds: float, what: str) -> Iterator[None]:
    """Raise :class:`StageTimeout` in the block after ``seconds`` (SIGALRM; main thread only)."""
    if seconds <= 0:
        yield
        return

    def fire(signum: int, frame: object) -> None:
        raise StageTimeout(f"{what} ran past {seconds:g} s")

    old = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


def _exception(exc: BaseException) -> str:
    msg = " ".join(str(exc).split())
    return f"exception: {type(exc).__name__}: {msg[:300]}"


def _count(v: Any) -> int | None:
    f = finite_or_none(v)
    return None if f is None else round(f)


def _task(job: Job) -> Any:
    from tooltransfer.problems.task import Variants, task_from_dict

    task = task_from_dict(job.data, job.source)
    return task.model_copy(update={"variants": Variants(oe=job.oe, ss=job.ss)})


def _mechanics(plan: Any, task: Any, source: str) -> Any:
    """The push mechanics the plan was made with (its metrics; the task's, for a plan without them)."""
    from tooltransfer.tools.pushing.mechanics import PushMechanics

    mu, c = finite_or_none(plan.metrics.get("mechanics_mu")), finite_or_none(plan.metrics.get("mechanics_c"))
    if mu is not None and c is not None:
        return PushMechanics(mu, c, "given")
    from tooltransfer.planner.planning.setting import task_mechanics, task_skills

    return task_mechanics(task, task_skills(task, source, need_ss=False))


def _mechanics_source(job: Job) -> str | None:
    """Where the planner's mechanics for the job's task come from (``identified``, ``task``,
    ``default``; :func:`tooltransfer.planner.planning.setting.task_mechanics`), None when that cannot be told."""
    try:
        from tooltransfer.planner.planning.setting import task_mechanics, task_skills

        task = _task(job)
        need_ss = variant_registry.needs_ss_skill(task.variants.ss)
        return task_mechanics(task, task_skills(task, job.source, need_ss=need_ss)).source
    except Exception:
        return None


def model_prediction(plan: Any, execution: Any, mech: Any) -> tuple[float, float]:
    """The push model's prediction of an open-loop run: the tool poses MuJoCo executed (its recorded
    track) replayed through :func:`tooltransfer.tools.pushing.forward.simulate` with ``mech`` from the task's
    start. Returns the predicted final puck's distance to the recorded final puck [m] (the
    recording's object track is the true pose: the platform adds no camera noise) and the largest
    distance along the run (the prediction at the object's sample times)."""
    from tooltransfer.planner.planning.setting import setting_from_task
    from tooltransfer.problems.task import task_from_dict
    from tooltransfer.tools.pushing.forward import simulate

    task = task_from_dict(plan.task, "plan.task")
    setting = setting_from_task(task, mechanics=mech)
    ex = execution
    trace = simulate(setting.tool, ex.tool_pose, np.array(task.start), setting.radius, setting.mechanics)
    final = float(np.linalg.norm(trace.final - ex.object_xy[-1]))
    pred = np.column_stack([np.interp(ex.t_object, ex.t_tool, trace.object_xy[:, j]) for j in range(2)])
    return final, float(np.linalg.norm(pred - ex.object_xy, axis=1).max())


MISMATCH_PLANTS = ("sim friction", "model 0.6x", "model 1.4x")
"""The mismatched plants: the MuJoCo platform with tool friction 0.5 and table friction 0.2
(:data:`SIM_FRICTION`), the quasi-static push model with mu and c 0.6 and 1.4 times the plan's."""
SIM_FRICTION = {"tool_friction": 0.5, "table_friction": 0.2}
MODEL_SCALE = {"model 0.6x": 0.6, "model 1.4x": 1.4}
CAMERA_NOISE = 0.0015
"""Camera noise [m] per frame of the model plants (the MuJoCo plant's default)."""


def run_mismatch(plan: Any, job: Job, mech: Any) -> dict[str, Row]:
    """Execute a solved plan on each of :data:`MISMATCH_PLANTS`: open loop, and closed loop when the
    job runs it. Per plant: ``open_loop_status`` (``"ok"`` or the exception), ``open_loop_error``,
    ``closed_loop_status``, ``closed_loop_reason``, ``closed_loop_error``, ``closed_loop_n_replans``,
    ``closed_loop_replan_times``, ``mechanics`` ([mu, c] of the model plants) and ``wall`` [s]."""
    from tooltransfer.planner.execution.closed_loop import execute_closed_loop
    from tooltransfer.planner.execution.plant import ModelPlant
    from tooltransfer.planner.execution.simulate import simulate_plan, task_sim_config
    from tooltransfer.planner.planning.setting import setting_from_task
    from tooltransfer.problems.task import task_from_dict
    from tooltransfer.tools.pushing.forward import simulate
    from tooltransfer.tools.pushing.mechanics import PushMechanics

    task = task_from_dict(plan.task, "plan.task")
    setting = setting_from_task(task, mechanics=mech)
    tool = setting.tool
    start, target, radius = np.array(task.start), np.array(task.target), setting.radius
    out: dict[str, Row] = {}
    for name in MISMATCH_PLANTS:
        res: Row = {"open_loop_status": None, "open_loop_error": None, "closed_loop_status": None,
                    "closed_loop_reason": "", "closed_loop_error": None, "closed_loop_n_replans": None,
                    "closed_loop_replan_times": None, "mechanics": None}
        t0 = time.perf_counter()
        plant_mech = config = None
        try:
            if name == "sim friction":
                config = task_sim_config(task, **SIM_FRICTION)
            else:
                f = MODEL_SCALE[name]
                plant_mech = PushMechanics(f * mech.mu, f * mech.c, "given")
                res["mechanics"] = [plant_mech.mu, plant_mech.c]
        except Exception as exc:
            res["open_loop_status"] = res["closed_loop_status"] = _exception(exc)
            res["wall"] = time.perf_counter() - t0
            out[name] = res
            continue
        try:
            with _deadline(job.timeout, f"open loop on {name}"):
                if plant_mech is None:
                    err = simulate_plan(plan, config).final_error
                else:
                    final = simulate(tool, plan.tool_pose, start, radius, plant_mech).final
                    err = float(np.linalg.norm(final - target))
            res.update(open_loop_status="ok", open_loop_error=err)
        except Exception as exc:
            res["open_loop_status"] = _exception(exc)
        if job.closed_loop:
            try:
                with _deadline(job.timeout, f"closed loop on {name}"):
                    if plant_mech is None:
                        cl = execute_closed_loop(plan, seed=job.seed, config=config)
                    else:
                        plant = ModelPlant(tool, radius, plant_mech, start, plan.tool_pose[0],
                                           platform=setting.platform, camera_noise=CAMERA_NOISE,
                                           seed=job.seed)
                        cl = execute_closed_loop(plan, plant, seed=job.seed)
                res.update(closed_loop_status=cl.status, closed_loop_reason=cl.reason, closed_loop_error=cl.final_error,
                           closed_loop_n_replans=cl.n_replans, closed_loop_replan_times=list(cl.replan_times))
            except Exception as exc:
                res["closed_loop_status"] = _exception(exc)
        res["wall"] = time.perf_counter() - t0
        out[name] = res
    return out


def run_task(job: Job) -> Row:
    """Plan one task and execute a solved plan open and closed loop (and on the mismatched plants);
    the row of its measures (never raises for the task's own failures). Errors in m, times in s;
    absent measures are None."""
    started = time.perf_counter()
    row: Row = {"task_id": job.task_id, "kind": job.kind, "index": job.index, "tool": job.tool,
                "variant": job.variant, "n_obstacles": job.n_obstacles, "status": None, "reason": "",
                "plan_wall": None, "plan_cpu": None, "n_pushes": None, "n_switches": None, "duration": None,
                "n_recontacts": None, "self_consistency": None, "mechanics_mu": None, "mechanics_c": None,
                "mechanics_source": None,
                "friction_cone_margin_min": None, "contact_edge_margin_min": None,
                "open_loop_status": None, "open_loop_error": None, "open_loop_wall": None,
                "model_prediction_status": None, "model_prediction_error": None, "model_prediction_track_max": None,
                "closed_loop_status": None, "closed_loop_reason": "", "closed_loop_error": None,
                "closed_loop_wall": None, "closed_loop_n_pushes": None, "closed_loop_n_switches": None,
                "closed_loop_n_recontacts": None, "closed_loop_n_replans": None, "closed_loop_replan_times": None,
                "mismatch": None, "mismatch_wall": None, "worker": os.getpid()}
    from tooltransfer.planner.planning.solve import solve

    wall, cpu = time.perf_counter(), time.process_time()
    try:
        with _deadline(job.timeout, "planning"):
            plan = solve(_task(job), job.source)
    except Exception as exc:
        now = time.perf_counter()
        row.update(status=_exception(exc), plan_wall=now - wall, task_wall=now - started)
        return row
    m = plan.metrics
    row.update(status=plan.status, reason=plan.reason or "", plan_wall=time.perf_counter() - wall,
               plan_cpu=time.process_time() - cpu, n_pushes=_count(m.get("n_pushes")),
               n_recontacts=_count(m.get("n_recontacts")),
               self_consistency=finite_or_none(m.get("self_consistency_max")),
               mechanics_mu=finite_or_none(m.get("mechanics_mu")),
               mechanics_c=finite_or_none(m.get("mechanics_c")),
               friction_cone_margin_min=finite_or_none(m.get("friction_cone_margin_min")),
               contact_edge_margin_min=finite_or_none(m.get("contact_edge_margin_min")),
               mechanics_source=_mechanics_source(job),
               time_skills=finite_or_none(m.get("time_skills")), time_oe=finite_or_none(m.get("time_oe")),
               time_switches_and_timing=finite_or_none(m.get("time_switches_and_timing")))
    if plan.status == "solved":
        from tooltransfer.planner.execution.closed_loop import execute_closed_loop
        from tooltransfer.planner.execution.simulate import simulate_plan

        row.update(n_switches=len(plan.switches), duration=finite_or_none(m.get("duration")))
        mech = None
        try:
            mech = _mechanics(plan, _task(job), job.source)
            row.update(mechanics_mu=mech.mu, mechanics_c=mech.c)
        except Exception as exc:
            row["model_prediction_status"] = _exception(exc)
        t0 = time.perf_counter()
        rep = None
        try:
            with _deadline(job.timeout, "open loop"):
                rep = simulate_plan(plan)
            row.update(open_loop_status="ok", open_loop_error=rep.final_error)
        except Exception as exc:
            row["open_loop_status"] = _exception(exc)
        row["open_loop_wall"] = time.perf_counter() - t0
        if rep is not None and mech is not None:
            try:
                with _deadline(job.timeout, "model prediction"):
                    final, track = model_prediction(plan, rep.execution, mech)
                row.update(model_prediction_status="ok", model_prediction_error=final, model_prediction_track_max=track)
            except Exception as exc:
                row["model_prediction_status"] = _exception(exc)
        if job.closed_loop:
            t0 = time.perf_counter()
            try:
                with _deadline(job.timeout, "closed loop"):
                    cl = execute_closed_loop(plan, seed=job.seed)
                row.update(closed_loop_status=cl.status, closed_loop_reason=cl.reason, closed_loop_error=cl.final_error,
                           closed_loop_n_pushes=cl.n_pushes, closed_loop_n_switches=cl.n_switches,
                           closed_loop_n_recontacts=cl.n_recontacts, closed_loop_n_replans=cl.n_replans,
                           closed_loop_replan_times=list(cl.replan_times))
            except Exception as exc:
                row["closed_loop_status"] = _exception(exc)
            row["closed_loop_wall"] = time.perf_counter() - t0
        if job.mismatch:
            t0 = time.perf_counter()
            if mech is None:
                row["mismatch"] = {name: {"open_loop_status": row["model_prediction_status"],
                                          "closed_loop_status": row["model_prediction_status"] if job.closed_loop
                                          else None} for name in MISMATCH_PLANTS}
            else:
                row["mismatch"] = run_mismatch(plan, job, mech)
            row["mismatch_wall"] = time.perf_counter() - t0
        if job.faults and mech is not None:
            t0 = time.perf_counter()
            row["faults"] = run_faults(plan, mech, job.faults, job.fault_base, job.seed,
                                       lambda what: _deadline(job.timeout, what))
            row["faults_wall"] = time.perf_counter() - t0
    row["task_wall"] = time.perf_counter() - started
    return row


def warm_up(jobs: Sequence[tuple[dict[str, Any], str]]) -> None:
    """Import the planner and the platform and learn (or load) the skills the tasks name."""
    import tooltransfer.planner.execution.closed_loop
    import tooltransfer.planner.execution.simulate  # noqa: F401
    from tooltransfer.planner.planning.setting import task_skills
    from tooltransfer.problems.task import task_from_dict

    for data, source in jobs:
        task = task_from_dict(data, source)
        task_skills(task, source, need_ss=variant_registry.needs_ss_skill(task.variants.ss))


def _init_worker(skills: Sequence[tuple[dict[str, Any], str]]) -> None:
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's
    warm_up(skills)


def parse_variants(text: str) -> list[tuple[str, str]]:
    """``"qp/opt,mapping/opt"`` -> ``[("qp", "opt"), ("mapping", "opt")]``."""
    out = []
    for part in text.split(","):
        oe, _, ss = part.strip().partition("/")
        if oe not in OE_VARIANTS or ss not in SS_VARIANTS:
            raise argparse.ArgumentTypeError(f"variants as oe/ss pairs (oe in {OE_VARIANTS}, ss in {SS_VARIANTS}), "
                                             f"not {part.strip()!r}")
        if (oe, ss) not in out:
            out.append((oe, ss))
    return out


def make_jobs(batch: Path, count: int | None, variants: Sequence[tuple[str, str]], paper: bool,
              closed_loop: bool, seed: int, timeout: float, mismatch: bool = True, faults: tuple[str, ...] = (),
              fault_base: str = "sim") -> list[Job]:
    """The jobs: the paper tasks first (their closed loops are the longest), then the generated
    tasks in order, each with every variant."""
    import yaml

    from tooltransfer.planner.apps.batch.generate import generate_tasks
    from tooltransfer.planner.apps.batch.spec import load_batch
    from tooltransfer.problems.task import load_task, task_obstacles

    spec = load_batch(batch)
    tasks = generate_tasks(spec, batch)
    if count is not None:
        tasks = tasks[:count]
    jobs = []
    for oe, ss in variants:
        common = {"oe": oe, "ss": ss, "closed_loop": closed_loop, "mismatch": mismatch, "seed": seed,
                  "timeout": timeout, "faults": faults, "fault_base": fault_base}
        for p in PAPER if paper else ():
            task = load_task(p)
            tool = task.tool if isinstance(task.tool, str) else task.tool.name
            jobs.append(Job(task.name, "paper", tool, -1, len(task_obstacles(task)), yaml.safe_load(p.read_text()),
                            str(p), **common))
        jobs += [Job(g.task_id, "generated", g.tool, g.index, g.n_obstacles, g.data, str(batch), **common)
                 for g in tasks]
    return jobs


def _progress_line(done: int, total: int, r: Row) -> str:
    def mm(v: float | None) -> str:
        return "-" if v is None else f"{1e3 * v:.1f} mm"

    s = f"[{done:>3}/{total}] {r['task_id']:<16} {r['tool']:<9} {r['variant']:<11} {r['status']}"
    if r["status"] == "solved":
        s += f" plan {r['plan_wall']:.2f} s | open {mm(r['open_loop_error'])}"
        if r["open_loop_status"] != "ok":
            s += f" ({r['open_loop_status']})"
        if r.get("model_prediction_error") is not None:
            s += f" | model {mm(r['model_prediction_error'])}"
        if r["closed_loop_status"] is not None:
            s += f" | closed {r['closed_loop_status']} {mm(r['closed_loop_error'])}"
        for name, res in (r.get("mismatch") or {}).items():
            cl = res.get("closed_loop_status")
            s += f" | {name} open {mm(res.get('open_loop_error'))}"
            if cl is not None:
                s += f" closed {cl if _is_exc(cl) else cl + ' ' + mm(res.get('closed_loop_error'))}"
        for name, res in (r.get("faults") or {}).items():
            s += f" | {name} {res.get('status') or 'exception'} {mm(res.get('error'))}"
    s += f" | {r.get('task_wall') or 0.0:.1f} s"
    return s


def run_jobs(jobs: Sequence[Job], workers: int, on_row: Callable[[Row], None] | None = None,
             run: Callable[[Job], Row] = run_task) -> list[Row]:
    """Every job's row (``run(job)``, by default :func:`run_task`; a module-level function, so that
    the workers can unpickle it), in the jobs' order, from a process pool of ``workers`` (1: in this
    process). When a worker dies (the pool breaks), the jobs it took down are run again one by one,
    each in a pool of its own; a job whose worker dies then becomes a ``crash`` row."""
    skills = list({(j.data["skills"].get("dataset"), j.source): (j.data, j.source) for j in jobs}.values())
    warm_up(skills)  # learn once here, so the workers load the skills from the cache
    rows: dict[int, Row] = {}

    def done(i: int, row: Row) -> None:
        rows[i] = row
        if on_row:
            on_row(row)

    if workers <= 1:
        for i, job in enumerate(jobs):
            done(i, run(job))
        return [rows[i] for i in range(len(jobs))]
    ctx = multiprocessing.get_context("spawn")

    def pool(n: int) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(n, mp_context=ctx, initializer=_init_worker, initargs=(skills,))

    broken = []
    with pool(workers) as ex:
        futures: dict[Future[Row], int] = {ex.submit(run, job): i for i, job in enumerate(jobs)}
        pending = set(futures)
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                i = futures[fut]
                try:
                    done(i, fut.result())
                except BrokenProcessPool:
                    broken.append(i)
                except Exception as exc:  # pickling and the like
                    done(i, _crash_row(jobs[i], _exception(exc)))
    for i in sorted(broken):
        with pool(1) as ex:
            try:
                done(i, ex.submit(run, jobs[i]).result())
            except BrokenProcessPool:
                done(i, _crash_row(jobs[i], "the worker process died"))
            except Exception as exc:
                done(i, _crash_row(jobs[i], _exception(exc)))
    return [rows[i] for i in range(len(jobs))]


def _crash_row(job: Job, why: str) -> Row:
    return {"task_id": job.task_id, "kind": job.kind, "index": job.index, "tool": job.tool, "variant": job.variant,
            "n_obstacles": job.n_obstacles, "status": f"crash: {why}", "reason": "", "plan_wall": None,
            "plan_cpu": None, "n_pushes": None, "open_loop_status": None, "open_loop_error": None,
            "closed_loop_status": None, "closed_loop_error": None, "task_wall": None, "mismatch": None}


# ---------------------------------------------------------------------------------------------- report


def _reason_group(reason: str) -> str:
    """A reason with its numbers replaced by ``#``, so that reasons of one kind group together."""
    return re.sub(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", "#", reason or "(no reason given)")


def error_stats(errors: Sequence[float | None], n_plans: int) -> dict[str, float | int | None]:
    """Median, p90 and max [m] of the measured errors, and the share of ``n_plans`` within each of
    :data:`WITHIN` (an unmeasured plan counts as a miss)."""
    e = np.array([v for v in errors if v is not None], dtype=float)
    out: dict[str, float | int | None] = {"n": len(e), "median": None, "p90": None, "max": None}
    if len(e):
        out.update(median=float(np.median(e)), p90=float(np.percentile(e, 90)), max=float(e.max()))
    for w in WITHIN:
        out[f"within_{round(1e3 * w)}mm"] = (float(np.sum(e <= w)) / n_plans) if n_plans else None
    return out


def _mm(v: float | None) -> str:
    return "-" if v is None else f"{1e3 * v:.1f}"


def _share(errors: Sequence[float | None], n: int, within: float) -> float | None:
    """The share of ``n`` runs with an error within ``within`` [m] (an unmeasured one a miss)."""
    return sum(e is not None and e <= within for e in errors) / n if n else None


def _quantiles(values: Sequence[float]) -> tuple[float, float, float] | None:
    """Median, p90 and max of ``values`` (None when empty)."""
    if not values:
        return None
    v = np.asarray(values, dtype=float)
    return float(np.median(v)), float(np.percentile(v, 90)), float(v.max())


def _statuses(statuses: Sequence[str | None]) -> str:
    c = Counter("exception" if _is_exc(s) else s for s in statuses if s is not None)
    return ", ".join(f"{s} {n}" for s, n in c.most_common()) or "-"


def _met(ok: bool) -> str:
    return "met" if ok else "MISSED"


MISMATCH_WITHIN = 0.003
"""Final-error threshold [m] of the mismatched plants' shares."""


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.0f} %"


def _is_exc(status: str | None) -> bool:
    return bool(status) and status.startswith(("exception:", "crash:"))


def _plant_runs(solved: Sequence[Row], name: str | None) -> list[Row]:
    """Per solved plan, its runs on one plant (None: the nominal platform) with the keys of
    :func:`run_mismatch`; plans that did not run on it are left out."""
    if name is None:
        return [{k: r.get(k) for k in ("open_loop_status", "open_loop_error", "closed_loop_status",
                                       "closed_loop_reason", "closed_loop_error", "closed_loop_n_replans",
                                       "closed_loop_replan_times")} for r in solved]
    return [r["mismatch"][name] for r in solved if r.get("mismatch") and name in r["mismatch"]]


def _mismatch_table(con: Any, solved: Sequence[Row]) -> None:
    """The plants table (the nominal platform and :data:`MISMATCH_PLANTS`) and the targets."""
    from rich import box
    from rich.table import Table

    w = MISMATCH_WITHIN
    t = Table("plant", "plans", f"open {1e3 * w:.0f}mm", f"closed {1e3 * w:.0f}mm", "closed 2mm",
              "median mm", "max mm", "re-plans", "re-plan ms", "closed-loop statuses",
              title=f"plants (open/closed Nmm: share within N mm of the solved plans, an exception a miss; median, "
                    f"max: closed loop; MuJoCo mu: tool/table friction; "
                    f"model fx: the push model with the plan's mu/c times f, camera {1e3 * CAMERA_NOISE:.1f} mm; "
                    f"re-plan ms: median/p90)",
              box=box.SIMPLE_HEAD, title_justify="left")
    shares: dict[str, tuple[float | None, float | None]] = {}
    times_all: dict[str, list[float]] = {}
    exc = {}
    notes: list[str] = []
    for name in (None, *MISMATCH_PLANTS):
        res = _plant_runs(solved, name)
        if not res:
            continue
        key = name or "nominal"
        cl_res = [x for x in res if x.get("closed_loop_status") is not None]
        cl = [None if _is_exc(x.get("closed_loop_status")) else x.get("closed_loop_error") for x in cl_res]
        st = error_stats(cl, len(cl_res))
        times = [v for x in cl_res for v in (x.get("closed_loop_replan_times") or [])]
        q = _quantiles(times)
        times_all[key] = times
        exc[key] = sum(_is_exc(x.get(f"{s}_status")) for x in res for s in ("open_loop", "closed_loop"))
        if name is None:
            label = "MuJoCo nominal"
        elif name == "sim friction":
            label = f"MuJoCo mu {SIM_FRICTION['tool_friction']}/{SIM_FRICTION['table_friction']}"
        else:
            label = f"model {name[6:]}"
            mechs = {tuple(x.get("mechanics") or ()) for x in res}
            if len(mechs) == 1 and len(m := next(iter(mechs))) == 2:
                notes.append(f"{label}: mu {m[0]:.3g}, c {m[1]:.3g}")
        misses = [f"{r['task_id']} {x.get('closed_loop_status')} {_mm(x.get('closed_loop_error'))}"
                  for r in solved for x in _plant_runs([r], name)
                  if x.get("closed_loop_status") is not None
                  and (x.get("closed_loop_error") is None or x["closed_loop_error"] > w)]
        if misses:
            notes.append(f"closed loop beyond {1e3 * w:.0f} mm on {label} (mm): " + ", ".join(misses))
        shares[key] = (_share(cl, len(cl_res), w) if cl_res else None,
                       _share(cl, len(cl_res), 0.002) if cl_res else None)
        t.add_row(label, str(len(res)), _pct(_share([x.get("open_loop_error") for x in res], len(res), w)),
                  _pct(shares[key][0]), _pct(shares[key][1]), _mm(st["median"]), _mm(st["max"]),
                  str(sum(x.get("closed_loop_n_replans") or 0 for x in cl_res)) if cl_res else "-",
                  "-" if q is None else f"{1e3 * q[0]:.0f}/{1e3 * q[1]:.0f}",
                  _statuses([x.get("closed_loop_status") for x in cl_res]))
    con.print(t)
    for note in notes:
        con.print("  " + note)
    for r in solved:
        for name, x in (r.get("mismatch") or {}).items():
            for stage in ("open_loop", "closed_loop"):
                if _is_exc(x.get(f"{stage}_status")):
                    con.print(f"  {stage.replace('_', ' ')} on {name} of {r['task_id']}: {x[f'{stage}_status']}")
    fails = Counter(f"{name}: {_reason_group(x.get('closed_loop_reason', ''))}" for r in solved
                    for name, x in (r.get("mismatch") or {}).items() if x.get("closed_loop_status") == "failed")
    for reason, n in fails.most_common(5):
        con.print(f"  failed x{n} on {reason}")
    nom = shares.get("nominal", (None, None))[1]
    if nom is None:
        return
    con.print("targets:")
    con.print(f"  closed loop on the nominal platform >= 95 % within 2 mm: {_pct(nom)} {_met(nom >= 0.95)}; "
              f"exceptions (open and closed loop) {exc['nominal']} {_met(exc['nominal'] == 0)}")
    for name in MISMATCH_PLANTS:
        v = shares.get(name, (None, None))[0]
        if v is not None:
            con.print(f"  closed loop on {name} >= 90 % within {1e3 * w:.0f} mm: {_pct(v)} {_met(v >= 0.9)}; "
                      f"exceptions {exc[name]}")
    for what, times in (("nominal platform", times_all.get("nominal", [])),
                        ("all plants", [v for ts in times_all.values() for v in ts])):
        q = _quantiles(times)
        if q is not None:
            con.print(f"  re-plan median <= 30 ms ({what}, {len(times)} re-plans): {1e3 * q[0]:.1f} ms "
                      f"{_met(q[0] <= 0.03)} (p90 {1e3 * q[1]:.1f} ms, max {1e3 * q[2]:.1f} ms)")


def report(rows: Sequence[Row], wall: float, console: Any | None = None) -> None:
    """Print the tables of the rows (module docstring), one section per variant."""
    from rich import box
    from rich.console import Console
    from rich.table import Table

    con = console or Console(markup=False, highlight=False)
    mechs = Counter((r["mechanics_mu"], r["mechanics_c"], r.get("mechanics_source") or "?") for r in rows
                    if r.get("mechanics_mu") is not None and r.get("mechanics_c") is not None)
    if mechs:
        def n_solved(key: tuple[float, float, str]) -> int:
            return sum((r.get("mechanics_mu"), r.get("mechanics_c"), r.get("mechanics_source") or "?") == key
                       and r["status"] == "solved" for r in rows)

        con.print("push mechanics of the plans (mu, c, source): " + "; ".join(
            f"({mu:.4g}, {c:.4g}, {src}) in {n} plans with metrics, {n_solved((mu, c, src))} solved"
            for (mu, c, src), n in mechs.most_common()))
    for variant in dict.fromkeys(r["variant"] for r in rows):
        vrows = [r for r in rows if r["variant"] == variant]
        gen = [r for r in vrows if r["kind"] == "generated"]
        solved = [r for r in gen if r["status"] == "solved"]
        infeasible = [r for r in gen if r["status"] in ("infeasible", "unknown", "violated")]
        certified = sum(r["status"] == "infeasible" for r in gen)
        failed = [r for r in gen if _is_exc(r["status"])]
        con.rule(f"variant {variant}")
        if gen:
            con.print(f"generated tasks: solved {len(solved)}/{len(gen)} ({_pct(len(solved) / len(gen))}), "
                      f"not solved {len(infeasible)} (certified infeasible {certified}, the rest unknown), "
                      f"planner exceptions {len(failed)}")
            plan_t = [r["plan_wall"] for r in gen if r["plan_wall"] is not None]
            if plan_t:
                con.print(f"planning wall time per task: median {np.median(plan_t):.2f} s, "
                          f"p90 {np.percentile(plan_t, 90):.2f} s, max {max(plan_t):.2f} s; "
                          f"CPU total {sum(r['plan_cpu'] or 0.0 for r in gen):.1f} s")
        if infeasible or failed:
            t = Table("count", "reason (numbers as #)", title="reasons of the unsolved (top 8) and planner exceptions",
                      box=box.SIMPLE_HEAD, title_justify="left")
            groups = Counter(_reason_group(r["reason"]) for r in infeasible)
            for reason, n in groups.most_common(8):
                t.add_row(str(n), reason)
            rest = sum(groups.values()) - sum(n for _, n in groups.most_common(8))
            if rest:
                other = len(groups) - 8
                t.add_row(str(rest), f"({other} other reason{'s' if other > 1 else ''})")
            for r in failed:
                t.add_row("1", f"{r['task_id']}: {r['status']}")
            con.print(t)
        if solved:
            t = Table("execution", "n", "median mm", "p90 mm", "max mm", "<= 2 mm", "<= 5 mm", "exceptions",
                      title=f"final error over the {len(solved)} solved plans (shares of all solved plans)",
                      box=box.SIMPLE_HEAD, title_justify="left")
            ol = error_stats([r["open_loop_error"] for r in solved], len(solved))
            t.add_row("open loop", str(ol["n"]), _mm(ol["median"]), _mm(ol["p90"]), _mm(ol["max"]),
                      _pct(ol["within_2mm"]), _pct(ol["within_5mm"]),
                      str(sum(_is_exc(r["open_loop_status"]) for r in solved)))
            ran_cl = [r for r in solved if r["closed_loop_status"] is not None]
            if ran_cl:
                cl = error_stats([r["closed_loop_error"] for r in ran_cl], len(ran_cl))
                t.add_row("closed loop", str(cl["n"]), _mm(cl["median"]), _mm(cl["p90"]), _mm(cl["max"]),
                          _pct(cl["within_2mm"]), _pct(cl["within_5mm"]),
                          str(sum(_is_exc(r["closed_loop_status"]) for r in ran_cl)))
            con.print(t)
            pred = [r["model_prediction_error"] for r in solved if r.get("model_prediction_error") is not None]
            q = _quantiles(pred)
            sc = [r["self_consistency"] for r in solved if r.get("self_consistency") is not None]
            if q is not None:
                track = [r["model_prediction_track_max"] for r in solved
                         if r.get("model_prediction_track_max") is not None]
                con.print(f"model prediction error (the push model replaying the tool poses MuJoCo executed open "
                          f"loop, final puck vs recorded) over {len(pred)} plans: median {_mm(q[0])} mm, "
                          f"p90 {_mm(q[1])} mm, max {_mm(q[2])} mm; "
                          f"largest along a run {_mm(max(track) if track else None)} mm")
            if sc:
                con.print(f"self-consistency of the plans: max {_mm(max(sc))} mm, "
                          f"median {_mm(float(np.median(sc)))} mm; "
                          f"re-contacts planned {sum(r.get('n_recontacts') or 0 for r in solved)} "
                          f"(in {sum((r.get('n_recontacts') or 0) > 0 for r in solved)} plans)")
            for r in solved:
                if _is_exc(r.get("model_prediction_status")):
                    con.print(f"  model prediction of {r['task_id']}: {r['model_prediction_status']}")
            if ran_cl:
                statuses = Counter("exception" if _is_exc(r["closed_loop_status"]) else r["closed_loop_status"]
                                   for r in ran_cl)
                con.print("closed-loop statuses: " + ", ".join(f"{s} {n}" for s, n in statuses.most_common()))
                times = [t for r in ran_cl for t in (r.get("closed_loop_replan_times") or [])]
                q = _quantiles(times)
                n_rp = [r.get("closed_loop_n_replans") or 0 for r in ran_cl]
                con.print(f"closed-loop re-plans: {sum(n_rp)} in {sum(n > 0 for n in n_rp)} of {len(ran_cl)} runs"
                          + ("" if q is None else f"; re-plan time median {1e3 * q[0]:.1f} ms, "
                             f"p90 {1e3 * q[1]:.1f} ms, max {1e3 * q[2]:.1f} ms")
                          + f"; re-contacts {sum(r.get('closed_loop_n_recontacts') or 0 for r in ran_cl)}, "
                          f"switches {sum(r.get('closed_loop_n_switches') or 0 for r in ran_cl)}")
                exec_t = [r["closed_loop_wall"] for r in ran_cl if r["closed_loop_wall"] is not None]
                con.print(f"closed-loop wall time per plan: median {np.median(exec_t):.1f} s, max {max(exec_t):.1f} s; "
                          f"open loop median {np.median([r['open_loop_wall'] for r in solved]):.1f} s")
                fails = Counter(_reason_group(r["closed_loop_reason"]) for r in ran_cl
                                if r["closed_loop_status"] == "failed")
                for reason, n in fails.most_common(5):
                    con.print(f"  failed x{n}: {reason}")
            for r in solved:
                for stage in ("open_loop", "closed_loop"):
                    if _is_exc(r[f"{stage}_status"]):
                        con.print(f"  {stage.replace('_', ' ')} of {r['task_id']}: {r[f'{stage}_status']}")
            _mismatch_table(con, solved)
            fault_table(con, [r for r in vrows if r["status"] == "solved"])  # the paper tasks too
        if gen:
            t = Table("tool", "tasks", "solved", "open median mm", "open <= 5 mm", "model pred. median mm",
                      "closed median mm", "closed <= 2 mm", title="per tool (shares of the tool's solved plans)",
                      box=box.SIMPLE_HEAD, title_justify="left")
            for tool in dict.fromkeys(r["tool"] for r in gen):
                tr = [r for r in gen if r["tool"] == tool]
                ts = [r for r in tr if r["status"] == "solved"]
                ol = error_stats([r["open_loop_error"] for r in ts], len(ts))
                cl_rows = [r for r in ts if r["closed_loop_status"] is not None]
                cl = error_stats([r["closed_loop_error"] for r in cl_rows], len(cl_rows))
                mp = [r["model_prediction_error"] for r in ts if r.get("model_prediction_error") is not None]
                t.add_row(tool, str(len(tr)), str(len(ts)), _mm(ol["median"]), _pct(ol["within_5mm"]),
                          _mm(float(np.median(mp)) if mp else None), _mm(cl["median"]), _pct(cl["within_2mm"]))
            con.print(t)
        paper = [r for r in vrows if r["kind"] == "paper"]
        if paper:
            t = Table("paper task", "tool", "status", "plan s", "pushes", "open loop mm", "model pred. mm",
                      "closed loop mm", "closed-loop status", "closed mm mismatched",
                      title="paper tasks (closed mm mismatched: " + " / ".join(MISMATCH_PLANTS) + ")",
                      box=box.SIMPLE_HEAD, title_justify="left")
            for r in paper:
                plan_s = "-" if r["plan_wall"] is None else f"{r['plan_wall']:.2f}"
                ol = _mm(r["open_loop_error"]) if not _is_exc(r["open_loop_status"]) else r["open_loop_status"]
                t.add_row(r["task_id"], r["tool"], r["status"] if r["status"] == "solved" else
                          f"{r['status']}: {r['reason']}", plan_s, "-" if r["n_pushes"] is None else
                          str(r["n_pushes"]), ol, _mm(r.get("model_prediction_error")), _mm(r["closed_loop_error"]),
                          r["closed_loop_status"] or "-", " / ".join(
                              _mm(res.get("closed_loop_error")) if not _is_exc(res.get("closed_loop_status"))
                              else "exc" for res in (r.get("mismatch") or {}).values()) or "-")
            con.print(t)
    slow = sorted((r for r in rows if r.get("task_wall") is not None), key=lambda r: -r["task_wall"])[:5]
    if slow:
        t = Table("task", "variant", "status", "task s", "plan s", "open s", "closed s", "mismatch s",
                  title="slowest tasks", box=box.SIMPLE_HEAD, title_justify="left")

        def sec(v: float | None) -> str:
            return "-" if v is None else f"{v:.1f}"

        for r in slow:
            t.add_row(r["task_id"], r["variant"], r["status"], sec(r["task_wall"]), sec(r["plan_wall"]),
                      sec(r.get("open_loop_wall")), sec(r.get("closed_loop_wall")), sec(r.get("mismatch_wall")))
        con.print(t)
    busy = sum(r.get("task_wall") or 0.0 for r in rows)
    con.print(f"total: {len(rows)} task runs in {wall:.1f} s wall ({wall / 60:.1f} min); "
              f"sum of task times {busy:.1f} s")


def _commit() -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True, check=True)
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return out.stdout.strip() + ("+dirty" if dirty else "")


def _clean(v: Any) -> Any:
    if isinstance(v, float | np.floating):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_clean(x) for x in v]
    return v


def write_json(path: Path, rows: Sequence[Row], meta: dict[str, Any]) -> None:
    """``{"meta": ..., "rows": [...]}``; non-finite numbers as null."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_clean({"meta": meta, "rows": list(rows)}), indent=1, allow_nan=False))


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--batch", type=Path, default=BATCH, help="batch file of the generated tasks")
    ap.add_argument("--count", type=int, default=None, help="only the first N generated tasks")
    ap.add_argument("--variants", type=parse_variants, default=[("qp", "opt")],
                    help="oe/ss pairs, comma-separated (default qp/opt), e.g. qp/opt,mapping/opt")
    ap.add_argument("--workers", type=int, default=2, help="worker processes (1: in this process)")
    ap.add_argument("--no-closed-loop", dest="closed_loop", action="store_false", help="skip the closed loop")
    ap.add_argument("--no-mismatch", dest="mismatch", action="store_false",
                    help="skip the mismatched plants (MuJoCo with other frictions, the push model with mu, c off)")
    ap.add_argument("--faults", type=parse_faults, default=(),
                    help="closed loop on these fault plants too: comma-separated names or 'all' "
                         "(tooltransfer.planner.execution.fault_plants.FAULTS)")
    ap.add_argument("--fault-base", choices=FAULT_BASES, default="sim",
                    help="the plant the faults wrap: the MuJoCo platform (sim) or the push model (model)")
    ap.add_argument("--no-paper", dest="paper", action="store_false", help="skip the two paper tasks")
    ap.add_argument("--seed", type=int, default=0, help="camera-noise seed of the closed loop")
    ap.add_argument("--timeout", type=float, default=600.0,
                    help="per task stage (planning, open loop, closed loop) [s], recorded as an exception; 0: none")
    ap.add_argument("--json", type=Path, default=None, help="write every per-task row to this file")
    ap.add_argument("--quiet", action="store_true", help="no line per finished task")
    args = ap.parse_args(argv)

    from rich.console import Console

    con = Console(width=None if sys.stdout.isatty() else 150, markup=False, highlight=False)
    t0 = time.perf_counter()
    jobs = make_jobs(args.batch, args.count, args.variants, args.paper, args.closed_loop, args.seed, args.timeout,
                     args.mismatch, args.faults, args.fault_base)
    variants = ",".join(f"{o}/{s}" for o, s in args.variants)
    commit = _commit()
    con.print(f"execution benchmark: {len(jobs)} task runs ({args.batch.name}"
              f"{'' if args.count is None else f', first {args.count}'}{' + paper tasks' if args.paper else ''}; "
              f"variants {variants}; closed loop {'on, seed ' + str(args.seed) if args.closed_loop else 'off'}; "
              f"mismatched plants {'on' if args.mismatch else 'off'}; "
              f"fault plants {', '.join(args.faults) + ' on ' + args.fault_base if args.faults else 'off'}); "
              f"{args.workers} workers")
    from tooltransfer.planner.learning.skills import cache_dir

    con.print(f"commit {commit}; skills cache {cache_dir()}")
    done = 0

    def on_row(r: Row) -> None:
        nonlocal done
        done += 1
        if not args.quiet:
            print(_progress_line(done, len(jobs), r), flush=True)

    rows = run_jobs(jobs, args.workers, on_row)
    wall = time.perf_counter() - t0
    report(rows, wall, con)
    if args.json is not None:
        meta = {"commit": commit, "batch": str(args.batch), "count": args.count, "variants": variants,
                "closed_loop": args.closed_loop, "mismatch": args.mismatch, "seed": args.seed,
                "faults": list(args.faults), "fault_base": args.fault_base,
                "workers": args.workers, "timeout": args.timeout,
                "wall": wall, "python": sys.version.split()[0], "argv": sys.argv[1:],
                "finished": time.strftime("%Y-%m-%d %H:%M:%S")}
        write_json(args.json, rows, meta)
        con.print(f"rows written to {args.json}")


if __name__ == "__main__":
    main()
