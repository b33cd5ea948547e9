"""Batch runs: process pool and Dask LocalCluster on one code path, one row per (task, variant),
failures become rows, a run killed with SIGKILL (or stopped with Ctrl-C) resumes without losing or
recomputing anything, and the report's statistics and files."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml

from tooltransfer.planner.apps.batch.executors import open_executor
from tooltransfer.planner.apps.batch.report import summarize, write_report
from tooltransfer.planner.apps.batch.runner import run_batch, run_jobs
from tooltransfer.planner.apps.batch.stats import wilson
from tooltransfer.planner.apps.batch.store import ResultStore
from tooltransfer.planner.apps.batch.worker import Job
from tooltransfer.planner.apps.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "problems" / "data" / "finger_demos"


def _batch(tmp_path: Path, name: str = "t", count: int = 3, oe: tuple = ("mapping",), **extra) -> Path:
    data = yaml.safe_load((ROOT / "problems" / "batch" / "small.yaml").read_text())
    data.update(name=name, count=count, dataset=str(DATASET), variants={"oe": list(oe), "ss": ["arch"]}, **extra)
    p = tmp_path / f"{name}.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def _rows(db: Path) -> list[tuple]:
    with sqlite3.connect(db) as c:
        sql = "SELECT task_id, variant, status, finished_at FROM results ORDER BY task_id, variant"
        return c.execute(sql).fetchall()


def test_pool_and_dask_give_the_same_rows_once_each(tmp_path) -> None:
    # seed 22: three quick tasks whose six rows hold all three verdicts (the batch file's seed 7: 28 s a run)
    batch = _batch(tmp_path, count=3, oe=("mapping", "qp"), seed=22)
    pool = run_batch(batch, tmp_path / "pool.sqlite", workers=2, progress=False)
    dask = run_batch(batch, tmp_path / "dask.sqlite", dask_local=2, progress=False)
    assert (pool.kind, dask.kind, pool.slots, dask.slots) == ("process pool", "dask", 2, 2)
    a, b = _rows(tmp_path / "pool.sqlite"), _rows(tmp_path / "dask.sqlite")
    assert len(a) == len(b) == 6 == pool.stored == dask.stored
    assert [r[:3] for r in a] == [r[:3] for r in b]  # same keys and statuses: the planner is deterministic
    assert {r[2] for r in a} == {"solved", "infeasible", "unknown"}
    with ResultStore(tmp_path / "pool.sqlite") as s:
        rows = s.rows()
    assert {r["tool"] for r in rows} == {"slope", "finger"} and all(r["time_total"] > 0 for r in rows)
    assert all(r["n_obstacles"] is not None and r["reach_margin"] is not None for r in rows)
    # a finished store: nothing to do on resume, refused without it, refused for another batch
    again = run_batch(batch, tmp_path / "pool.sqlite", workers=2, resume=True, progress=False)
    assert (again.stored, again.skipped) == (0, 6)
    assert main(["batch", "run", str(batch), "--db", str(tmp_path / "pool.sqlite"), "-q"]) == 2
    other = _batch(tmp_path, name="other")
    assert main(["batch", "run", str(other), "--db", str(tmp_path / "pool.sqlite"), "-q", "--resume"]) == 2


def test_scheduler_address_connects_to_a_running_cluster(tmp_path) -> None:
    """--scheduler ADDRESS: the same runner on an existing cluster (here in-process worker threads, each
    with its own sandbox)."""
    from distributed import LocalCluster

    jobs = [Job(f"j{i}", "v", entry="builtins:dict", args=({"status": "solved", "reason": str(i)},), timeout=30)
            for i in range(5)]
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        with ResultStore(tmp_path / "r.sqlite") as store, open_executor(scheduler=cluster.scheduler_address) as slots:
            assert (slots.kind, slots.slots) == ("dask", 2)
            s = run_jobs(jobs, store, slots, progress=False)
            rows = store.rows()
    assert s.stored == 5 and sorted(r["reason"] for r in rows) == [str(i) for i in range(5)]
    assert len({r["worker"] for r in rows}) == 1  # one worker process, two threads


def test_failures_become_rows_and_the_batch_goes_on(tmp_path) -> None:
    jobs = [Job("a", "v", entry="math:hypot", args=(1.0, 1.0), timeout=10),  # not a row
            Job("b", "v", entry="time:sleep", args=(30,), timeout=1.0),
            Job("c", "v", entry="os:_exit", args=(9,), timeout=10),
            Job("d", "v", entry="operator:truediv", args=(1, 0), timeout=10),
            Job("e", "v", entry="builtins:dict", args=({"status": "solved", "reason": ""},), timeout=10)]
    with ResultStore(tmp_path / "r.sqlite") as store, open_executor(workers=2) as slots:
        s = run_jobs(jobs, store, slots, progress=False)
        rows = {r["task_id"]: r for r in store.rows()}
    assert s.stored == 5 and not s.interrupted
    assert [rows[k]["status"] for k in "abcde"] == ["error", "timeout", "error", "error", "solved"]
    assert "exited with code 9" in rows["c"]["reason"] and "ZeroDivisionError" in rows["d"]["reason"]


def test_a_killed_worker_process_is_replaced(tmp_path) -> None:
    """A job that kills its pool worker (the sandbox's parent) breaks the pool: the pool is replaced,
    the other running jobs run again, and the job that killed it twice becomes an error row."""
    killer = ["sh", "-c", "kill -9 $(ps -o ppid= -p $PPID)"]  # sh's parent is the sandbox; its parent, the worker
    jobs = [Job(f"k{i}", "v", entry="builtins:dict", args=({"status": "solved"},), timeout=10) for i in range(6)]
    jobs.insert(2, Job("victim", "v", entry="subprocess:call", args=(killer,), timeout=10))
    with ResultStore(tmp_path / "r.sqlite") as store, open_executor(workers=2) as slots:
        s = run_jobs(jobs, store, slots, progress=False)
        rows = {r["task_id"]: r for r in store.rows()}
    assert s.stored == 7 and set(rows) == {"victim", *(f"k{i}" for i in range(6))}
    assert rows["victim"]["status"] == "error" and "died twice" in rows["victim"]["reason"]
    assert all(rows[f"k{i}"]["status"] == "solved" for i in range(6))


def _spawn(args: list[str]) -> subprocess.Popen:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.Popen([sys.executable, "-m", "tooltransfer.planner.apps.cli", *args], env=env,
                            stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def _wait_rows(db: Path, n: int, proc: subprocess.Popen, limit: float = 90.0) -> None:
    end = time.monotonic() + limit
    while time.monotonic() < end:
        if db.is_file():
            try:
                if len(_rows(db)) >= n:
                    return
            except sqlite3.OperationalError:
                pass
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    raise AssertionError(f"fewer than {n} rows after {limit} s")


def _children(pid: int) -> list[int]:
    out = subprocess.run(["ps", "-o", "pid=", "--ppid", str(pid)], capture_output=True, text=True).stdout
    return [int(x) for x in out.split()]


@pytest.mark.serial  # a real SIGKILL must land while the run is under way
def test_sigkill_mid_run_then_resume_stores_each_pair_once_and_recomputes_nothing(tmp_path) -> None:
    batch = _batch(tmp_path, name="kill", count=7)
    db = tmp_path / "kill.sqlite"
    proc = _spawn(["batch", "run", str(batch), "--db", str(db), "--workers", "2", "-q"])
    try:
        _wait_rows(db, 3, proc)
        workers = _children(proc.pid)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
        before = _rows(db)
        assert 3 <= len(before) < 7
        # the orphaned pool workers and their sandboxes notice and exit on their own
        end = time.monotonic() + 10
        while time.monotonic() < end and any(os.path.exists(f"/proc/{w}") and
                                             "Z" not in open(f"/proc/{w}/stat").read().split()[2] for w in workers):
            time.sleep(0.1)
        assert not [w for w in workers if os.path.exists(f"/proc/{w}")
                    and open(f"/proc/{w}/stat").read().split()[2] != "Z"]
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    res = _spawn(["batch", "run", str(batch), "--db", str(db), "--workers", "2", "-q", "--resume"])
    out, err = res.communicate(timeout=120)
    assert res.returncode == 0, err
    assert f"{len(before)} already done, of 7" in out
    after = _rows(db)
    assert sorted((t, v) for t, v, *_ in after) == sorted({(t, v) for t, v, *_ in after})  # each once
    assert {t for t, *_ in after} == {f"kill-{i:05d}" for i in range(7)}
    assert set(before) <= set(after)  # finished rows untouched: same status and completion time


@pytest.mark.serial  # a real SIGINT must land while the run is under way
def test_ctrl_c_stops_cleanly_and_resume_finishes(tmp_path) -> None:
    # the runner keeps up to 2 jobs per slot in flight (4 here) and the first Ctrl-C lets them finish:
    # with 7 jobs, the 5 left after the second row were all in flight or next, so every row could be
    # stored before the interrupt took effect; with 12 at most about 2 + 1 + 4 are
    count = 12
    batch = _batch(tmp_path, name="intr", count=count)
    db = tmp_path / "intr.sqlite"
    proc = _spawn(["batch", "run", str(batch), "--db", str(db), "--workers", "2", "-q"])
    _wait_rows(db, 2, proc)
    os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C does: the whole foreground group
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "--resume" in out and "Traceback" not in err
    n = len(_rows(db))
    assert 2 <= n < count
    assert main(["batch", "run", str(batch), "--db", str(db), "--workers", "2", "-q", "--resume"]) == 0
    assert len({(t, v) for t, v, *_ in _rows(db)}) == len(_rows(db)) == count


@pytest.mark.serial  # the stop comes 1.5 s in, while jobs run
def test_stop_event_drains_running_jobs(tmp_path) -> None:
    jobs = [Job(f"s{i}", "v", entry="time:sleep", args=(0.3,), timeout=10) for i in range(40)]
    stop = threading.Event()
    with ResultStore(tmp_path / "r.sqlite") as store, open_executor(workers=2) as slots:
        threading.Timer(1.5, stop.set).start()
        s = run_jobs(jobs, store, slots, progress=False, stop=stop, catch_sigint=False)
        assert s.interrupted and 0 < store.count() < 30
        assert {r["status"] for r in store.rows()} == {"error"}  # sleep returns None: "not a row"


def test_report_statistics_and_files(tmp_path, capsys) -> None:
    lo, hi = wilson(7, 10)
    # Wilson score interval by its formula, z = 1.959964
    z, p, n = 1.959964, 0.7, 10
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z / (1 + z * z / n) * (p * (1 - p) / n + z * z / (4 * n * n)) ** 0.5
    assert (lo, hi) == pytest.approx((c - h, c + h), abs=1e-6)
    db = tmp_path / "r.sqlite"
    with ResultStore(db) as store:
        store.add_tasks([{"task_id": f"t{i}", "idx": i, "tool": "slope", "n_obstacles": i % 3,
                          "reach_margin": 0.001 * i} for i in range(10)])
        for i in range(10):
            status = "solved" if i < 7 else ("infeasible" if i < 9 else "timeout")
            store.put({"task_id": f"t{i}", "variant": "qp/arch", "tool": "slope", "status": status,
                       "reason": f"reach: target {i} mm out" if status == "infeasible" else "",
                       "time_total": 0.1 * (i + 1), "cone_violation_max": 0.001 * i if status == "solved" else None,
                       "sim_success": int(i < 5) if status == "solved" else None})
        with pytest.raises(sqlite3.IntegrityError):
            store.put({"task_id": "t0", "variant": "qp/arch", "status": "solved"})
        rows = store.rows()
    s = {(g.tool, g.variant): g for g in summarize(rows)}[("slope", "qp/arch")]
    assert (s.n, s.solved, s.infeasible, s.timeout, s.rate) == (10, 7, 2, 1, 0.7)
    assert (s.ci_low, s.ci_high) == pytest.approx((lo, hi))
    assert s.time_p50 == pytest.approx(0.5) and s.cone_violation_max == pytest.approx(0.006)
    assert (s.sim_n, s.sim_success) == (7, 5) and s.valid == 7
    written = write_report(db, tmp_path / "rep")
    assert {p.name for p in written} == {"results.csv", "summary.csv", "reasons.csv", "success_vs_difficulty.png",
                                         "time_distributions.png", "report.html"}
    reasons = (tmp_path / "rep" / "reasons.csv").read_text()
    assert "reach: target 7 mm out" in reasons and "reach: target 8 mm out" in reasons  # whole, numbers kept
    assert len((tmp_path / "rep" / "results.csv").read_text().splitlines()) == 11
    assert "70.0" in capsys.readouterr().out
    assert main(["batch", "report", str(tmp_path / "missing.sqlite")]) == 2


def test_retry_runs_only_the_asked_statuses_and_never_loses_a_verdict(tmp_path, capsys) -> None:
    """``--retry``: the rows of those statuses run again, each kept until its new result comes; a new run
    that gives no verdict (error, timeout) does not replace a verdict already stored."""
    import sqlite3 as sql

    with ResultStore(tmp_path / "r.sqlite") as store:
        for i, status in enumerate(("solved", "infeasible", "error", "timeout", "unknown")):
            store.put({"task_id": f"t{i}", "variant": "v", "status": status, "reason": f"first {status}"})
        assert store.again(["error", "timeout", "unknown"]) == {("t2", "v"), ("t3", "v"), ("t4", "v")}
        assert store.count() == 5  # nothing is deleted before the new results come (a stopped retry loses none)
        assert store.put({"task_id": "t2", "variant": "v", "status": "solved", "reason": ""})
        assert store.put({"task_id": "t3", "variant": "v", "status": "timeout", "reason": "again 120 s"})
        assert not store.put({"task_id": "t4", "variant": "v", "status": "timeout", "reason": "no result in 120 s"})
        with pytest.raises(sql.IntegrityError):  # a row not being run again is never stored twice
            store.put({"task_id": "t0", "variant": "v", "status": "error"})
    with sql.connect(tmp_path / "r.sqlite") as c:
        rows = {t: (st, r, d) for t, st, r, d in c.execute("SELECT task_id, status, reason, detail FROM results")}
    assert {t: st for t, (st, _, _) in rows.items()} == {"t0": "solved", "t1": "infeasible", "t2": "solved",
                                                          "t3": "timeout", "t4": "unknown"}
    assert rows["t2"][2] == "replaces a row of an earlier run: error (first error)"
    assert rows["t3"][1] == "again 120 s"
    assert rows["t4"][1] == "first unknown"  # the verdict kept, and how the new run ended
    assert rows["t4"][2] == "run again, it ended timeout (no result in 120 s): this row is kept"
    batch = _batch(tmp_path)
    assert main(["batch", "run", str(batch), "--db", str(tmp_path / "x.sqlite"), "--resume", "--retry", "solved"]) == 2
    assert "--retry" in capsys.readouterr().err


def test_retry_unknown_with_a_larger_budget_runs_those_rows_again(tmp_path, capsys) -> None:
    """``--resume --retry unknown --budget K``: only the unknown rows run again, with the search's and the
    certificate's budgets multiplied by K (recorded in each row's evidence)."""
    import json

    # seed 22: two quick tasks the mapping variant leaves unknown, as the batch file's seed 7 does
    batch = _batch(tmp_path, count=2, seed=22)
    db = tmp_path / "r.sqlite"
    assert main(["batch", "run", str(batch), "--db", str(db), "-q", "--workers", "1"]) == 0
    with sqlite3.connect(db) as c:
        first = {t: (f, st) for t, f, st in c.execute("SELECT task_id, finished_at, status FROM results")}
        c.execute("UPDATE results SET status = 'unknown' WHERE task_id = 't-00000'")
    again = {t for t, (_, st) in first.items() if st == "unknown"} | {"t-00000"}
    assert main(["batch", "run", str(batch), "--db", str(db), "-q", "--workers", "1", "--resume",
                 "--retry", "unknown", "--budget", "3"]) == 0
    with sqlite3.connect(db) as c:
        sql = "SELECT task_id, finished_at, metrics_json FROM results"
        rows = {t: (f, json.loads(m)) for t, f, m in c.execute(sql)}
    assert rows.keys() == first.keys()
    for t, (finished, metrics) in rows.items():
        assert (finished != first[t][0]) == (t in again), t
        assert metrics["evidence"]["budget"] == (3.0 if t in again else 1.0), t
    # a retry that gives no verdict (every job past its timeout) keeps the verdicts stored, and says so
    sql = "SELECT task_id, status, reason, finished_at, detail FROM results ORDER BY task_id"
    with sqlite3.connect(db) as c:
        c.execute("UPDATE results SET status = 'unknown'")
        before = c.execute(sql).fetchall()
    capsys.readouterr()
    assert main(["batch", "run", str(batch), "--db", str(db), "-q", "--workers", "1", "--resume",
                 "--retry", "unknown", "--timeout", "0.001"]) == 1
    assert "2 of them ran again and gave no verdict (error or timeout)" in capsys.readouterr().out
    with sqlite3.connect(db) as c:
        after = c.execute(sql).fetchall()
    assert [r[:4] for r in after] == [r[:4] for r in before]
    assert all(r[4].endswith("run again, it ended timeout (no result within the timeout of 0.001 s): this row is "
                             "kept") for r in after)
    assert main(["batch", "run", str(batch), "--db", str(db), "-q", "--resume", "--budget", "0.5"]) == 2
