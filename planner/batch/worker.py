"""What an executor slot runs: :func:`run_job` takes a :class:`Job` and returns its result row.

The same function runs in a process-pool worker and in a Dask worker thread; each slot (thread)
keeps its own :class:`~planner.batch.sandbox.Sandbox`, so skills are loaded once per slot and a
hang or crash costs only that job. Every way a job can end becomes a row: the job's own measures,
an ``error`` (exception or crash, with the message), or a ``timeout``.
"""

from __future__ import annotations

import os
import signal
import socket
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from planner.batch.sandbox import Sandbox

_LOCAL = threading.local()


@dataclass(frozen=True)
class Job:
    """One (task, variant) to run.

    Attributes:
        task_id, variant: the row's key (``variant`` as ``"<oe>/<ss>"``).
        entry: ``"module:function"`` returning the row's measures (a dict with at least ``status``).
        args: its arguments (picklable).
        timeout: [s] for the call.
        warmup: calls a new sandbox runs first, untimed (imports, skills).
    """

    task_id: str
    variant: str
    entry: str = "planner.batch.execute:execute_job"
    args: tuple = ()
    timeout: float = 60.0
    warmup: tuple[tuple[str, tuple], ...] = field(default=(), repr=False)

    @property
    def key(self) -> tuple[str, str]:
        return (self.task_id, self.variant)


def _sandbox(warmup: tuple[tuple[str, tuple], ...]) -> Sandbox:
    box = getattr(_LOCAL, "sandbox", None)
    if box is None:
        box = _LOCAL.sandbox = Sandbox(warmup)
    return box


def run_job(job: Job) -> dict[str, Any]:
    """Run ``job`` in this slot's sandbox; the result row (never raises for the job's own failures)."""
    started = time.time()
    out = _sandbox(job.warmup).call(job.entry, job.args, job.timeout)
    row: dict[str, Any] = {"task_id": job.task_id, "variant": job.variant, "started_at": started,
                           "worker": f"{socket.gethostname()}:{os.getpid()}", "wall_time": out.wall}
    if out.kind == "ok" and isinstance(out.value, dict) and "status" in out.value:
        row.update(out.value)
    elif out.kind == "ok":
        row.update(status="error", reason=f"the job returned {type(out.value).__name__}, not a row")
    elif out.kind == "timeout":
        row.update(status="timeout", reason=out.message)
    else:
        row.update(status="error", reason=out.message, detail=out.detail[-8000:])
    row["finished_at"] = time.time()
    return row


def _watch_parent(ppid: int) -> None:
    while True:
        if os.getppid() != ppid:
            os._exit(3)
        time.sleep(0.5)


def pool_initializer() -> None:
    """Process-pool worker set-up: Ctrl-C is the runner's to handle; exit when the runner dies."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True).start()
