"""The sandbox isolates each job: a result, an exception, a hang (timeout) or a crash of the
interpreter each end as that job's row, and the next job runs in a fresh child."""

from __future__ import annotations

import pytest

from tooltransfer.planner.apps.batch.sandbox import Sandbox
from tooltransfer.planner.apps.batch.worker import Job, run_job


@pytest.fixture(scope="module")
def box():
    b = Sandbox()
    yield b
    b.close()


def test_results_exceptions_timeouts_and_crashes(box) -> None:
    out = box.call("math:hypot", (3.0, 4.0), timeout=30)
    assert (out.kind, out.value) == ("ok", 5.0)
    out = box.call("operator:truediv", (1, 0), timeout=30)
    assert out.kind == "exception" and out.message.startswith("ZeroDivisionError") and "Traceback" in out.detail
    starts = box.starts
    out = box.call("time:sleep", (30,), timeout=0.5)
    assert out.kind == "timeout" and "0.5 s" in out.message and not box.alive
    out = box.call("os:_exit", (7,), timeout=30)
    assert out.kind == "crash" and out.message == "the sandbox process exited with code 7"
    out = box.call("ctypes:string_at", (0,), timeout=30)  # a segmentation fault
    assert out.kind == "crash" and "SIGSEGV" in out.message
    assert box.call("math:hypot", (6.0, 8.0), timeout=30).value == 10.0
    assert box.starts == starts + 3  # a fresh child after the timeout and each crash


def test_prints_do_not_spoil_the_replies(box) -> None:
    out = box.call("builtins:print", ("noise on stdout",), timeout=30)
    assert out.kind == "ok" and out.value is None
    assert box.call("math:sqrt", (2.0,), timeout=30).value == pytest.approx(2 ** 0.5)


def test_warm_up_runs_untimed_in_each_new_child() -> None:
    b = Sandbox(warmup=(("time:sleep", (0.6,)),))
    try:
        assert b.call("math:floor", (2.5,), timeout=0.5).value == 2  # the 0.6 s warm-up is not timed
        b.call("os:_exit", (0,), timeout=5)
        assert b.call("math:floor", (3.5,), timeout=0.5).value == 3
        assert b.starts == 2
    finally:
        b.close()


def test_run_job_turns_every_ending_into_a_row() -> None:
    rows = [run_job(Job("t", "v", entry=e, args=a, timeout=1.0)) for e, a in (
        ("builtins:dict", ()),
        ("operator:truediv", (1, 0)),
        ("time:sleep", (20,)),
        ("os:abort", ()),
        ("math:hypot", (1.0, 1.0)),
    )]
    assert [r["status"] for r in rows] == ["error", "error", "timeout", "error", "error"]
    assert "not a row" in rows[0]["reason"] and "ZeroDivisionError" in rows[1]["reason"]
    assert "SIGABRT" in rows[3]["reason"] and "not a row" in rows[4]["reason"]
    assert all(r["finished_at"] >= r["started_at"] for r in rows)
