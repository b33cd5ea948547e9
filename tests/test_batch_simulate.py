"""Batch studies measure execution: ``batch run --simulate`` executes every solved plan open and
closed loop in the sandbox (each execution a call of its own: a failure is that stage's status),
stores the errors, statuses and times, refuses a resume with the other setting, and the report
gives executed success beside plan feasibility; schema-1 stores stay readable."""

from __future__ import annotations

import functools
import operator
import os
import sqlite3
import time
from pathlib import Path

import pytest
import yaml

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.jobs import batch_jobs
from tooltransfer.planner.apps.batch.report import EXEC_TOLS, summarize, write_report
from tooltransfer.planner.apps.batch.spec import batch_from_dict, load_batch
from tooltransfer.planner.apps.batch.store import RESULT_COLUMNS, ResultStore
from tooltransfer.planner.apps.batch.store_settings import open_batch_store
from tooltransfer.planner.apps.batch.worker import Job, Stage, run_job
from tooltransfer.planner.apps.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "problems" / "data" / "finger_demos"


def _batch(tmp_path: Path, name: str = "sim", count: int = 6, **extra) -> Path:
    data = yaml.safe_load((ROOT / "problems" / "batch" / "small.yaml").read_text())
    data.update(name=name, count=count, dataset=str(DATASET), variants={"oe": ["qp"], "ss": ["opt"]}, **extra)
    p = tmp_path / f"{name}.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def test_simulated_batch_through_the_cli_stores_both_executions_and_reports_them(tmp_path, capsys) -> None:
    # seed 22: four tasks solved, two certified infeasible, all quick (the batch file's seed 7 has a slow unknown)
    batch = _batch(tmp_path, seed=22)
    db = tmp_path / "sim.sqlite"
    assert main(["batch", "run", str(batch), "--db", str(db), "--workers", "2", "-q", "--simulate"]) == 0
    with ResultStore(db) as store:
        rows = store.rows()
        assert store.meta()["simulate"] == "on"
    assert len(rows) == 6
    solved = [r for r in rows if r["status"] == "solved"]
    assert 2 <= len(solved) < len(rows)  # at seed 22 four solve with qp/opt, two are infeasible
    for r in solved:
        assert r["open_loop_status"] == "done" and 0 <= r["open_loop_error"] < 0.05
        assert r["open_loop_error"] == r["sim_final_error"] and r["open_loop_wall_time"] > 0
        assert r["closed_loop_status"] in ("reached", "closest", "rounds", "failed")
        assert r["closed_loop_error"] is not None and r["closed_loop_replans"] >= 0
        assert r["closed_loop_wall_time"] > 0 and r["closed_loop_pushes"] >= 1
        assert r["closed_loop_seed"] == load_batch(batch).simulate.closed_loop_seed(r["idx"])
    for r in rows:
        if r["status"] != "solved":  # nothing to execute
            assert r["open_loop_status"] is None and r["closed_loop_status"] is None
    # the report: executed success beside feasibility, CSV and the figure
    capsys.readouterr()
    assert main(["batch", "report", str(db), "--out", str(tmp_path / "rep")]) == 0
    out = capsys.readouterr().out
    assert "executed success" in out and "CL <=2 mm" in out and "OL <=5 mm" in out and "reached" in out
    assert "t50 [ms]" in out  # units in the headers are text, not markup
    summary = (tmp_path / "rep" / "summary.csv").read_text()
    assert "cl_2mm_of_solved" in summary and "ol_5mm_of_all" in summary and "cl_statuses" in summary
    assert (tmp_path / "rep" / "executed_success.png").stat().st_size > 0
    assert "closed_loop_error" in (tmp_path / "rep" / "results.csv").read_text().splitlines()[0]
    s = {(g.tool, g.variant): g for g in summarize(rows)}[("all", "qp/opt")]
    assert s.ol_n == s.cl_n == s.solved == len(solved)
    k2 = sum(r["closed_loop_error"] <= EXEC_TOLS[0] for r in solved)
    assert s.cl_2mm == k2 and s.cl_2mm_of_solved == pytest.approx(k2 / len(solved))
    assert s.cl_2mm_of_all == pytest.approx(k2 / 6)
    # a resume with the other setting is refused, naming it; with the same one there is nothing to do
    assert main(["batch", "run", str(batch), "--db", str(db), "--workers", "2", "-q", "--resume"]) == 2
    err = capsys.readouterr().err
    assert "--simulate" in err and "simulate on" in err and "simulate off" in err
    assert main(["batch", "run", str(batch), "--db", str(db), "--workers", "1", "-q", "--resume", "--no-simulate"]) == 2
    assert main(["batch", "run", str(batch), "--db", str(db), "--workers", "1", "-q", "--resume", "--simulate"]) == 0
    assert "0 results stored (nothing to do), 6 already done" in capsys.readouterr().out


def test_the_setting_is_part_of_the_fingerprint_not_of_the_batch(tmp_path) -> None:
    """The batch file's simulate.enabled and --simulate are one setting: the digest leaves it out and
    the store records it; the other simulation fields are part of the batch."""
    base = yaml.safe_load(_batch(tmp_path).read_text())
    on = batch_from_dict({**base, "simulate": {"enabled": True}})
    off = batch_from_dict({**base, "simulate": {"enabled": False}})
    seeded = batch_from_dict({**base, "simulate": {"enabled": True, "seed": 3}})
    assert on.digest() == off.digest() != seeded.digest()
    tasks, jobs = batch_jobs(off, tmp_path / "sim.yaml", simulate=True)
    assert all([s.name for s in j.stages] == ["open_loop", "closed_loop"] for j in jobs)
    assert not any(j.stages for j in batch_jobs(on, tmp_path / "sim.yaml", tasks=tasks, simulate=False)[1])
    seeds = [on.simulate.closed_loop_seed(i) for i in range(4)]
    assert seeds == [on.simulate.closed_loop_seed(i) for i in range(4)] and len(set(seeds)) == 4
    assert seeds != [seeded.simulate.closed_loop_seed(i) for i in range(4)]
    with ResultStore(tmp_path / "r.sqlite") as store:
        open_batch_store(store, off, tasks, resume=False, simulate=True)
        store.put({"task_id": tasks[0].task_id, "variant": "qp/opt", "status": "infeasible"})
        open_batch_store(store, on, tasks, resume=True)  # the file's enabled: true is the same setting
        with pytest.raises(InputError, match=r"--simulate: .*simulate on.*got simulate off"):
            open_batch_store(store, off, tasks, resume=True)


def test_a_failing_execution_is_that_stage_status_and_the_row_keeps_its_plan(tmp_path) -> None:
    # each stage evaluates the job's "plan" ("f()") with its own f: columns, an exception, a crash, a hang
    def stage(name: str, f: object, timeout: float = 30) -> Stage:
        return Stage(name, "builtins:eval", ({"f": f},), timeout)

    stages = (stage("open_loop", functools.partial(dict, open_loop_error=0.001)),
              stage("closed_loop", functools.partial(operator.truediv, 1, 0)),
              stage("crashing", os.abort),
              stage("hanging", functools.partial(time.sleep, 30), timeout=0.5),
              stage("after", dict))
    row = run_job(Job("t", "qp/opt", entry="builtins:dict", args=({"status": "solved", "reason": "", "plan": "f()"},),
                      timeout=30, stages=stages))
    assert row["status"] == "solved" and "plan" not in row
    assert (row["open_loop_status"], row["open_loop_error"]) == ("done", 0.001)
    assert row["closed_loop_status"] == "error" and "ZeroDivisionError" in row["closed_loop_reason"]
    assert row["crashing_status"] == "error" and "SIGABRT" in row["crashing_reason"]
    assert row["hanging_status"] == "timeout" and "0.5 s" in row["hanging_reason"]
    assert row["after_status"] == "done"  # a fresh sandbox after the crash and the hang
    assert "closed_loop: Traceback" in row["detail"]
    assert all(row[f"{n}_wall_time"] >= 0 for n in ("open_loop", "closed_loop", "crashing", "hanging"))
    # stages run only after a solved call
    row = run_job(Job("u", "qp/opt", entry="builtins:dict", args=({"status": "infeasible", "plan": "f()"},),
                      timeout=30, stages=stages[:1]))
    assert row["status"] == "infeasible" and "open_loop_status" not in row and "plan" not in row
    # what a store keeps of it
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.put({**row, "task_id": "v"})
        store.put({"task_id": "w", "variant": "qp/opt", "status": "solved", "open_loop_status": "error",
                   "open_loop_reason": "RuntimeError: boom", "closed_loop_status": "timeout",
                   "closed_loop_reason": "no result within the timeout of 1 s"})
        rows = store.rows()
    s = {(g.tool, g.variant): g for g in summarize(rows)}[("all", "qp/opt")]
    assert (s.ol_n, s.ol_failed, s.ol_2mm, s.cl_n, s.cl_statuses) == (1, 1, 0, 1, "timeout 1")


def test_schema_1_stores_stay_readable_and_are_not_resumed(tmp_path, capsys) -> None:
    db = tmp_path / "old.sqlite"
    old = {k: v for k, v in RESULT_COLUMNS.items() if not k.startswith(("open_loop", "closed_loop"))}
    with sqlite3.connect(db) as c:
        c.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT)")
        c.execute("INSERT INTO meta VALUES ('schema', '1'), ('batch_name', 'old')")
        c.execute(f"CREATE TABLE results ({', '.join(f'{k} {v}' for k, v in old.items())}, "
                  "PRIMARY KEY (task_id, variant))")
        c.executemany("INSERT INTO results (task_id, variant, tool, status, sim_final_error, sim_success) "
                      "VALUES (?, ?, ?, ?, ?, ?)", [("a", "qp/opt", "slope", "solved", 0.0015, 1),
                                                    ("b", "qp/opt", "slope", "infeasible", None, None)])
    with ResultStore(db) as store:
        assert store.schema == "1"
        rows = {r["task_id"]: r for r in store.rows()}
        assert rows["a"]["open_loop_error"] == 0.0015 and rows["b"].get("open_loop_error") is None
        batch = load_batch(_batch(tmp_path))
        with pytest.raises(InputError, match="schema 1"):
            open_batch_store(store, batch, [], resume=True)
    capsys.readouterr()
    write_report(db, None)
    out = capsys.readouterr().out
    assert "executed success" in out and "1: 100 / 50" in out  # open loop within 2 mm of 1 solved, 2 tasks
