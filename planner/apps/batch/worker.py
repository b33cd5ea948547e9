"""What an executor slot runs: :func:`run_job` takes a :class:`Job` and returns its result row.

The same function runs in a process-pool worker and in a Dask worker thread; each slot (thread)
keeps its own :class:`~tooltransfer.planner.apps.batch.sandbox.Sandbox`, so skills are loaded once per slot and a
hang or crash costs only that job. Every way a job can end becomes a row: the job's own measures,
an ``error`` (exception or crash, with the message), or a ``timeout``. A call whose sandbox was
killed from outside (SIGKILL: the kernel's OOM killer, an operator) is made once more in a new
sandbox before its crash counts (:func:`call_surviving_kill`).

A job may have stages (:class:`Stage`, e.g. executing the plan open and closed loop) run after a
``solved`` call, each a sandbox call of its own with its own timeout, given what the job returned
under ``"plan"``: its columns join the row, and a stage that raises, hangs or crashes sets only its
``<stage>_status`` (``error`` or ``timeout``) and ``<stage>_reason``; the row keeps its status.

A job whose :attr:`Job.skills` names the batch's shipped skills (:mod:`tooltransfer.planner.apps.batch.shipping`)
plans with this slot's local copy of them: its calls (and the sandbox's warm-up) take the task's
skills from that file rather than from the dataset, which the worker then need not have.
"""

from __future__ import annotations

import os
import signal
import socket
import threading
import time
from dataclasses import dataclass, field, replace
from typing import Any

from tooltransfer.planner.apps.batch import shipping
from tooltransfer.planner.apps.batch.sandbox import Outcome, Sandbox

_LOCAL = threading.local()


@dataclass(frozen=True)
class Stage:
    """A call run after a job solved: ``entry(plan, *args)`` returning columns (a dict).

    Attributes:
        name: column prefix: ``<name>_status``, ``<name>_reason``, ``<name>_wall_time`` [s].
        entry: ``"module:function"``; args: after the job's ``"plan"`` value (picklable).
        timeout: [s] for the call.
    """

    name: str
    entry: str
    args: tuple = ()
    timeout: float = 120.0


@dataclass(frozen=True)
class Job:
    """One (task, variant) to run.

    Attributes:
        task_id, variant: the row's key (``variant`` as ``"<oe>/<ss>"``).
        entry: ``"module:function"`` returning the row's measures (a dict with at least ``status``).
        args: its arguments (picklable).
        timeout: [s] for the call.
        warmup: calls a new sandbox runs first, untimed (imports, skills).
        stages: run in turn when the call returns a ``solved`` row (module docstring).
        skills: the digest of the batch's shipped skills (:mod:`tooltransfer.planner.apps.batch.shipping`), or None
            (the task's own ``skills`` as they are: the dataset at its path).
    """

    task_id: str
    variant: str
    entry: str = "tooltransfer.planner.apps.batch.execute:execute_job"
    args: tuple = ()
    timeout: float = 60.0
    warmup: tuple[tuple[str, tuple], ...] = field(default=(), repr=False)
    stages: tuple[Stage, ...] = ()
    skills: str | None = None

    @property
    def key(self) -> tuple[str, str]:
        return (self.task_id, self.variant)


def _sandbox(warmup: tuple[tuple[str, tuple], ...]) -> Sandbox:
    box = getattr(_LOCAL, "sandbox", None)
    if box is None:
        box = _LOCAL.sandbox = Sandbox(warmup)
    return box


def run_job(job: Job) -> dict[str, Any]:
    """Run ``job`` (and its stages) in this slot's sandbox; the result row (never raises for the
    job's own failures)."""
    started = time.time()
    worker = f"{socket.gethostname()}:{os.getpid()}"
    args, warmup = job.args, job.warmup
    if job.skills is not None:
        path = shipping.local_path(job.skills)
        if path is None:
            return {"task_id": job.task_id, "variant": job.variant, "started_at": started, "worker": worker,
                    "wall_time": 0.0, "status": "error", "finished_at": time.time(),
                    "reason": f"the batch's skills ({job.skills}) were not shipped to this worker ({worker})"}
        args = shipping.localize(args, path)
        warmup = tuple((entry, shipping.localize(a, path)) for entry, a in warmup)
    box = _sandbox(warmup)
    out = call_surviving_kill(box, job.entry, args, job.timeout)
    row: dict[str, Any] = {"task_id": job.task_id, "variant": job.variant, "started_at": started,
                           "worker": worker, "wall_time": out.wall}
    if out.kind == "ok" and isinstance(out.value, dict) and "status" in out.value:
        row.update(out.value)
    elif out.kind == "ok":
        row.update(status="error", reason=f"the job returned {type(out.value).__name__}, not a row")
    elif out.kind == "timeout":
        row.update(status="timeout", reason=out.message)
    else:
        row.update(status="error", reason=out.message, detail=out.detail[-8000:])
    plan = row.pop("plan", None)
    if row["status"] == "solved" and plan is not None:
        details = []
        for stage in job.stages:
            cols = run_stage(box, stage, plan)
            if cols.get("detail"):
                details.append(f"{stage.name}: {cols.pop('detail')}")
            row.update(cols)
        if details:
            row["detail"] = "\n".join(details)[-8000:]
    row["finished_at"] = time.time()
    return row


def call_surviving_kill(box: Sandbox, entry: str, args: tuple, timeout: float) -> Outcome:
    """``box.call(entry, args, timeout)``, made once more in a new sandbox when the sandbox was killed
    by SIGKILL from outside (the kernel's OOM killer, an operator): such a death says nothing about
    the job. A second one is the job's outcome, its message saying it happened twice."""
    out = box.call(entry, args, timeout)
    if out.kind != "crash" or out.signal != signal.SIGKILL:
        return out
    again = box.call(entry, args, timeout)
    if again.kind == "crash" and again.signal == signal.SIGKILL:
        return replace(again, message=f"{again.message} twice (from outside: the kernel's OOM killer, or an operator?)")
    return again


def run_stage(box: Sandbox, stage: Stage, plan: Any) -> dict[str, Any]:
    """One stage in ``box``: its columns, or ``<name>_status`` ``error``/``timeout`` with the reason
    (and the traceback or the crashed child's stderr under ``detail``)."""
    out = call_surviving_kill(box, stage.entry, (plan, *stage.args), stage.timeout)
    cols: dict[str, Any] = {f"{stage.name}_wall_time": out.wall}
    if out.kind == "ok" and isinstance(out.value, dict):
        cols.update(out.value)
        cols.setdefault(f"{stage.name}_status", "done")
    elif out.kind == "ok":
        cols.update({f"{stage.name}_status": "error",
                     f"{stage.name}_reason": f"the stage returned {type(out.value).__name__}, not columns"})
    else:
        cols.update({f"{stage.name}_status": "timeout" if out.kind == "timeout" else "error",
                     f"{stage.name}_reason": out.message, "detail": out.detail[-4000:]})
    return cols


def _watch_parent(ppid: int) -> None:
    while True:
        if os.getppid() != ppid:
            os._exit(3)
        time.sleep(0.5)


def pool_initializer(skills: tuple[tuple[str, str], ...] = ()) -> None:
    """Process-pool worker set-up: Ctrl-C is the runner's to handle; exit when the runner dies;
    ``skills``: ``(digest, path)`` of the skills files the runner wrote
    (:mod:`tooltransfer.planner.apps.batch.shipping`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for digest, path in skills:
        shipping.register(digest, path)
    threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True).start()
