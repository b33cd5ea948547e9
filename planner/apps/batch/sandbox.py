"""A long-lived child process that runs calls in isolation, with a timeout.

Why: a batch must survive a task that hangs, crashes the interpreter (a solver's segfault, an
``os._exit``) or raises. Signals cannot interrupt a call in a Dask worker's thread, and a fresh
process per call would pay the imports and the skill loading each time. So each executor slot
(a process-pool worker or a Dask worker thread) keeps one sandbox: ``python -m
tooltransfer.planner.apps.batch.sandbox``, fed ``(entry, args)`` over a pipe
(:class:`multiprocessing.connection.Connection` framing). :meth:`Sandbox.call` waits at most ``timeout`` seconds; on a
timeout the child is killed (SIGKILL) and the next call starts a new one, which first runs the warm-up calls (imports,
skills) outside any timeout. The child ignores SIGINT (Ctrl-C is the batch runner's to handle), writes
anything printed to its stderr log (so fd 1 carries only the replies), and exits when its parent
dies.
"""

from __future__ import annotations

import importlib
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from dataclasses import dataclass
from multiprocessing.connection import Connection
from typing import Any, Literal

#: Warm-up calls get this long in all [s].
STARTUP_TIMEOUT = 600.0


@dataclass(frozen=True)
class Outcome:
    """How a call ended.

    Attributes:
        kind: ``ok`` (``value`` holds the return value), ``exception`` (``message`` names the type and
            text; ``detail`` holds the traceback's last 12 frames), ``timeout`` or ``crash`` (the child
            died: ``message`` names the signal or exit code, ``detail`` the tail of its stderr).
        wall: wall time of the call [s] (the timeout for a timeout).
        signal: for a crash, the signal that ended the child (0: it exited); ``SIGKILL`` is how the
            kernel's OOM killer and an operator's ``kill -9`` end a process.
    """

    kind: Literal["ok", "exception", "timeout", "crash"]
    value: Any = None
    message: str = ""
    detail: str = ""
    wall: float = 0.0
    signal: int = 0


def _resolve(entry: str) -> Any:
    module, _, name = entry.partition(":")
    return getattr(importlib.import_module(module), name)


class Sandbox:
    """A child process running ``(entry, args)`` calls; ``entry`` is ``"module:function"``.

    Args:
        warmup: calls run (untimed, results dropped) each time a child starts.
    """

    def __init__(self, warmup: tuple[tuple[str, tuple], ...] = ()) -> None:
        self.warmup = warmup
        self._proc: subprocess.Popen | None = None
        self._tx: Connection | None = None
        self._rx: Connection | None = None
        self._log: Any = None
        self.starts = 0

    @property
    def alive(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def _start(self) -> None:
        self.close()
        c_rx, p_tx = os.pipe()
        p_rx, c_tx = os.pipe()
        self._log = tempfile.TemporaryFile()
        env = {**os.environ, "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS", "1")}
        # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in its workers; inherited, it made the planner
        # spend 1.5x the CPU (glibc returning memory after every numpy temporary), so the child goes without
        env.pop("MALLOC_TRIM_THRESHOLD_", None)
        self._proc = subprocess.Popen([sys.executable, "-m", "tooltransfer.planner.apps.batch.sandbox"], stdin=c_rx,
                                      stdout=c_tx, stderr=self._log, close_fds=True, env=env)
        os.close(c_rx)
        os.close(c_tx)
        self._tx, self._rx = Connection(p_tx, readable=False), Connection(p_rx, writable=False)
        self.starts += 1
        try:  # the child says it is ready: its start-up is not part of any call's timeout
            if not self._rx.poll(STARTUP_TIMEOUT) or self._rx.recv() != "ready":
                raise EOFError
        except (EOFError, OSError):
            self.kill()
            return
        warmup, deadline = self.warmup, time.monotonic() + STARTUP_TIMEOUT
        for entry, args in warmup:
            out = self._call(entry, args, max(1.0, deadline - time.monotonic()))
            if out.kind in ("timeout", "crash"):
                self.warmup = ()  # do not repeat a warm-up that kills the child
                return

    def _tail(self) -> str:
        if self._log is None:
            return ""
        self._log.seek(0, os.SEEK_END)
        size = self._log.tell()
        self._log.seek(max(0, size - 2000))
        return self._log.read().decode(errors="replace").strip()

    def _call(self, entry: str, args: tuple, timeout: float) -> Outcome:
        assert self._tx is not None and self._rx is not None and self._proc is not None
        start = time.perf_counter()
        try:
            self._tx.send((entry, args))
            ready = self._rx.poll(timeout)
            if not ready:
                self.kill()
                return Outcome("timeout", message=f"no result within the timeout of {timeout:g} s", wall=timeout)
            reply = self._rx.recv()
        except (EOFError, OSError):
            code = self._proc.wait()
            why = f"killed by {signal.Signals(-code).name}" if code < 0 else f"exited with code {code}"
            detail = self._tail()
            self.close()
            return Outcome("crash", message=f"the sandbox process {why}", detail=detail,
                           wall=time.perf_counter() - start, signal=-code if code < 0 else 0)
        kind, value, message, detail = reply
        return Outcome(kind, value, message, detail, time.perf_counter() - start)

    def call(self, entry: str, args: tuple = (), timeout: float = 60.0) -> Outcome:
        """Run ``entry(*args)`` in the child (starting one if needed) within ``timeout`` [s]."""
        if not self.alive:
            self._start()
            if not self.alive:
                self._start()  # the warm-up killed it: start once more, without warm-up
            if not self.alive:
                return Outcome("crash", message="the sandbox process did not start", detail=self._tail())
        return self._call(entry, args, timeout)

    def kill(self) -> None:
        """Kill the child now (SIGKILL) and release its pipes."""
        if self._proc is not None and self._proc.poll() is None:
            self._proc.kill()
            self._proc.wait()
        self.close()

    def __del__(self) -> None:
        try:
            self.kill()
        except Exception:  # interpreter shutdown: the child exits on its own (its input closes)
            pass

    def close(self) -> None:
        """Let the child exit (its input closes) and release the pipes and the log."""
        for c in (self._tx, self._rx):
            if c is not None:
                c.close()
        if self._proc is not None:
            try:
                self._proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        if self._log is not None:
            self._log.close()
        self._tx = self._rx = self._proc = self._log = None


def _watch_parent(ppid: int) -> None:
    while True:
        if os.getppid() != ppid:
            os._exit(3)
        time.sleep(0.5)


def _child_main() -> None:  # pragma: no cover - runs in the child process
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    out_fd = os.dup(1)
    os.dup2(2, 1)  # prints (Python or C) go to the log, not into the replies
    sys.stdout = sys.stderr
    rx, tx = Connection(0, writable=False), Connection(out_fd, readable=False)
    threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True).start()
    tx.send("ready")
    while True:
        try:
            entry, args = rx.recv()
        except (EOFError, OSError):
            break
        try:
            reply = ("ok", _resolve(entry)(*args), "", "")
        except Exception as exc:
            tb = "".join(traceback.format_exception(exc, limit=-12))
            reply = ("exception", None, f"{type(exc).__name__}: {exc}", tb)
        try:
            tx.send(reply)
        except Exception as exc:  # an unpicklable return value
            tx.send(("exception", None, f"{type(exc).__name__}: the result could not be sent back: {exc}", ""))


if __name__ == "__main__":  # pragma: no cover
    _child_main()
