"""A Ctrl-C that lands inside CasADi's IPOPT solve stays a Ctrl-C (issue 16, class 4): CasADi alone
returns a failed solve (``NonIpopt_Exception_Thrown``), which the planner would take for an
infeasible start; :func:`keep_interrupts` raises it again once the solver returns."""

from __future__ import annotations

import os
import signal
import threading
import time

import casadi as ca
import pytest

from tooltransfer.planner.ss.interrupts import keep_interrupts


def _slow_nlp():  # a chain Rosenbrock that IPOPT needs seconds for at this tolerance
    n = 12000
    x = ca.SX.sym("x", n)
    f = 100 * ca.sumsqr(x[1:] - x[:-1] ** 2) + ca.sumsqr(1 - x[:-1])
    g = ca.vertcat(*[x[i] ** 2 + x[i + 1] ** 2 for i in range(0, n - 1, 3)])
    opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.max_iter": 100000,
            "ipopt.tol": 1e-14}
    return ca.nlpsol("slow", "ipopt", {"x": x, "f": f, "g": g}, opts)


def _interrupt_soon() -> None:
    threading.Timer(0.15, lambda: os.kill(os.getpid(), signal.SIGINT)).start()


def test_casadi_alone_swallows_the_interrupt_and_keep_interrupts_raises_it() -> None:
    solver = _slow_nlp()
    _interrupt_soon()
    t0 = time.perf_counter()
    solver(x0=0.5, lbg=0, ubg=1.5)  # returns: CasADi caught the KeyboardInterrupt
    assert solver.stats()["return_status"] == "NonIpopt_Exception_Thrown"
    assert time.perf_counter() - t0 < 30
    _interrupt_soon()
    with pytest.raises(KeyboardInterrupt), keep_interrupts():
        solver(x0=0.5, lbg=0, ubg=1.5)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handler is put back


def test_without_an_interrupt_nothing_changes() -> None:
    x = ca.MX.sym("x", 2)
    solver = ca.nlpsol("quick", "ipopt", {"x": x, "f": ca.sumsqr(x - 1)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"})
    with keep_interrupts():
        sol = solver(x0=0)
    assert solver.stats()["success"] and abs(float(sol["x"][0]) - 1) < 1e-8
