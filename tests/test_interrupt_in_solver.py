"""A Ctrl-C that lands inside a solver that swallows it stays a Ctrl-C (issue 16, class 4). CasADi's
IPOPT interface catches the ``KeyboardInterrupt`` raised inside the solve and returns a failed solve
(``return_status`` ``"NonIpopt_Exception_Thrown"``, seen with casadi 3.7 on a 40,000-variable
Rosenbrock chain interrupted after 0.5 s), which the planner would take for an infeasible start;
:func:`keep_interrupts` raises it again once the solver returns. A solver that swallows the interrupt
is played here by a function doing what CasADi does (a real IPOPT solve may end before the signal
arrives on a fast machine, so timing one is not a deterministic test)."""

from __future__ import annotations

import os
import signal
import time

import casadi as ca
import pytest

from tooltransfer.planner.planning.ss.interrupts import keep_interrupts

pytestmark = pytest.mark.serial  # a real SIGINT to this process, answered within a bounded time


def _swallowing_solver() -> str:
    """Like CasADi's nlpsol under a Ctrl-C: the interrupt arrives while it runs and is turned into a status."""
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(5.0)  # the handler raises KeyboardInterrupt here
    except KeyboardInterrupt:
        return "NonIpopt_Exception_Thrown"
    return "Solve_Succeeded"


def test_a_swallowed_interrupt_is_raised_again_after_the_solver() -> None:
    assert _swallowing_solver() == "NonIpopt_Exception_Thrown"  # alone, the interrupt is lost
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt), keep_interrupts():
        _swallowing_solver()
    assert time.perf_counter() - t0 < 2.0
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handler is put back


def test_without_an_interrupt_nothing_changes() -> None:
    x = ca.MX.sym("x", 2)
    solver = ca.nlpsol("quick", "ipopt", {"x": x, "f": ca.sumsqr(x - 1)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"})
    with keep_interrupts():
        sol = solver(x0=0)
    assert solver.stats()["success"] and abs(float(sol["x"][0]) - 1) < 1e-8
