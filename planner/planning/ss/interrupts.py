"""A Ctrl-C during a CasADi solve stays a Ctrl-C.

CasADi's IPOPT interface catches the ``KeyboardInterrupt`` that Python's signal handler raises
inside the solve and returns a failed solve (``return_status`` ``"NonIpopt_Exception_Thrown"``),
so the planner would take it for an infeasible start and go on, and the command would end with
exit 1 instead of 130. :func:`keep_interrupts` notes the signal and raises it again after the solve.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType


@contextmanager
def keep_interrupts() -> Iterator[None]:
    """Around a solver call: a SIGINT during it raises :class:`KeyboardInterrupt` once it returns.
    Only in the main thread with Python's default handler in place (elsewhere it does nothing)."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    hit: list[int] = []

    def note(signum: int, frame: FrameType | None) -> None:
        hit.append(signum)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, note)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if hit:
        raise KeyboardInterrupt
