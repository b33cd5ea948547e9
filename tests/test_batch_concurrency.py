"""Batch at scale and in parallel (issue 16, class 8): two ``batch run`` processes on one store (the
second is refused at once by the store's lock, the first finishes with each pair exactly once and a
resume afterwards leaves every finished row untouched), a batch of a million tasks generated as it runs,
a corrupt dataset refused before the run, Dask workers that cannot run the jobs and an address where no
scheduler answers refused with a message, and a run whose every job failed exits non-zero."""

from __future__ import annotations

import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.spec import load_batch
from tooltransfer.planner.apps.batch.store import ResultStore, lock_store
from tooltransfer.planner.apps.cli import main

ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "problems" / "data" / "finger_demos"


def _batch(tmp_path: Path, name: str = "conc", count: int = 4, dataset: Path = DATASET, **extra) -> Path:
    data = yaml.safe_load((ROOT / "problems" / "batch" / "small.yaml").read_text())
    data.update(name=name, count=count, dataset=str(dataset), variants={"oe": ["mapping"], "ss": ["arch"]}, **extra)
    p = tmp_path / f"{name}.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def _spawn(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "tooltransfer.planner.apps.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})


def _all_rows(db: Path) -> list[tuple]:
    with sqlite3.connect(db) as c:
        return c.execute("SELECT * FROM results ORDER BY task_id, variant").fetchall()


@pytest.mark.serial  # refused within 10 s while the first run, a real process, still holds the store
def test_a_second_run_on_a_store_in_use_is_refused_and_the_first_keeps_each_pair_once(tmp_path, capsys) -> None:
    batch = _batch(tmp_path)
    db = tmp_path / "conc.sqlite"
    first = _spawn(["batch", "run", str(batch), "--db", str(db), "--workers", "1", "-q"])
    try:
        end = time.monotonic() + 60
        lock = db.with_name(db.name + ".lock")  # the holder writes its pid there once it holds the lock
        while not (lock.is_file() and f"process {first.pid} " in lock.read_text()):
            assert first.poll() is None and time.monotonic() < end, first.communicate()
            time.sleep(0.05)
        for extra in ([], ["--resume"]):  # refused at once either way, naming the store and its holder
            start = time.perf_counter()
            assert main(["batch", "run", str(batch), "--db", str(db), "--workers", "1", "-q", *extra]) == 2
            assert time.perf_counter() - start < 10
            err = capsys.readouterr().err
            assert f"--db {db}:" in err and f"in use by process {first.pid}" in err and "Traceback" not in err, err
        _, err = first.communicate(timeout=120)
        assert first.returncode == 0, err
    finally:
        if first.poll() is None:
            os.killpg(first.pid, signal.SIGKILL)
    rows = _all_rows(db)
    keys = [(r[0], r[1]) for r in rows]
    assert len(keys) == len(set(keys)) == 4  # each pair exactly once
    # the lock went with the first run; a resume finds nothing to do and touches no finished row
    assert main(["batch", "run", str(batch), "--db", str(db), "--workers", "1", "-q", "--resume"]) == 0
    assert "0 results stored" in capsys.readouterr().out
    assert _all_rows(db) == rows


def test_the_lock_goes_with_a_killed_holder(tmp_path) -> None:
    db = tmp_path / "k.sqlite"
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time\n"
                               "from tooltransfer.planner.apps.batch.store import lock_store\n"
                               f"with lock_store({str(db)!r}):\n    print('held', flush=True)\n    time.sleep(60)"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(InputError, match=f"in use by process {holder.pid}"):
            with lock_store(db):
                pass
        holder.kill()
        holder.wait(timeout=10)
        with lock_store(db):
            pass
    finally:
        holder.kill()


def test_a_million_tasks_are_generated_as_the_run_goes(tmp_path) -> None:
    from tooltransfer.planner.apps.batch.generate import generate_task
    from tooltransfer.planner.apps.batch.jobs import lazy_jobs, warmup_calls

    batch = _batch(tmp_path, name="huge", count=1_000_000)
    spec = load_batch(batch)
    first = generate_task(spec, 0, str(DATASET))
    start = time.perf_counter()
    with ResultStore(tmp_path / "huge.sqlite") as store:
        jobs = lazy_jobs(spec, batch, store, first, None, None, warmup_calls(spec, batch, first, None))
        got = [next(jobs) for _ in range(10)]
        assert time.perf_counter() - start < 5
        with sqlite3.connect(store.path) as c:
            assert c.execute("SELECT COUNT(*) FROM tasks").fetchone()[0] == 64  # stored as they are generated
    assert [j.task_id for j in got] == [f"huge-{i:05d}" for i in range(10)]
    # batch generate: bounded, --first N writes the first N
    assert main(["batch", "generate", str(batch), "--out", str(tmp_path / "tasks")]) == 2
    assert main(["batch", "generate", str(batch), "--out", str(tmp_path / "tasks"), "--first", "3"]) == 0
    assert len(list((tmp_path / "tasks").glob("*.yaml"))) == 3


@pytest.mark.serial  # rows within 60 s, then a real SIGINT
def test_a_million_task_run_stores_rows_within_seconds_and_stops_cleanly(tmp_path) -> None:
    batch = _batch(tmp_path, name="mega", count=1_000_000)
    db = tmp_path / "mega.sqlite"
    proc = _spawn(["batch", "run", str(batch), "--db", str(db), "--workers", "1", "-q"])
    try:
        end, n = time.monotonic() + 60, 0
        while n < 2 and time.monotonic() < end and proc.poll() is None:
            time.sleep(0.2)
            try:
                n = len(_all_rows(db))
            except sqlite3.OperationalError:
                pass
        assert n >= 2, proc.communicate(timeout=10)
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 130 and "--resume" in out and "of 1000000" in out, err
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)


def _corrupt(tmp_path: Path, how: str) -> Path:
    from test_hostile_data_cases import CASES, copy_dataset

    folder = copy_dataset(tmp_path / f"ds_{how.replace(' ', '_')}")
    CASES[how][0](folder)
    return folder


@pytest.mark.parametrize("how, where", [("duplicate obj_x", "demo_00.csv"), ("tool i_shape", "meta.yaml"),
                                        ("joints in degrees", "demo_00.csv")])
def test_a_corrupt_dataset_is_refused_before_the_run(tmp_path, capsys, how: str, where: str) -> None:
    folder = _corrupt(tmp_path, how)
    db = tmp_path / "bad.sqlite"
    assert main(["batch", "run", str(_batch(tmp_path, dataset=folder)), "--db", str(db), "--workers", "1", "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{folder}/{where}" in err and "Traceback" not in err and err.count("\n") == 1, err
    assert not db.exists()  # nothing half-written


def test_a_dask_worker_without_the_package_is_refused_before_the_first_job(tmp_path, capsys) -> None:
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=0, dashboard_address=None, protocol="tcp", host="127.0.0.1") as cluster:
        addr = cluster.scheduler_address
        code = ("import sys; sys.modules['tooltransfer'] = None\n"
                f"sys.argv = ['dask-worker', {addr!r}, '--nthreads', '1', '--no-nanny', '--no-dashboard']\n"
                "from distributed.cli.dask_worker import main; main()")
        worker = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            with Client(addr) as client:
                client.wait_for_workers(1, timeout=30)
            db = tmp_path / "d.sqlite"
            assert main(["batch", "run", str(_batch(tmp_path)), "--db", str(db), "--scheduler", addr, "-q"]) == 2
            err = capsys.readouterr().err
            assert "--scheduler" in err and "cannot be imported" in err and "Traceback" not in err, err
            assert not db.exists()  # refused before the store was made: no job ran
        finally:
            worker.kill()
            worker.wait(timeout=10)


def test_dask_workers_that_cannot_read_the_dataset_are_refused() -> None:
    from distributed import Client, LocalCluster

    from tooltransfer.planner.apps.batch.dask_plugin import check_workers

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        check_workers(client, "--scheduler", str(DATASET))
        with pytest.raises(InputError, match="no dataset at /nowhere"):
            check_workers(client, "--scheduler", "/nowhere")


@pytest.mark.serial  # refused within 10 s
def test_an_address_where_no_scheduler_answers_is_refused_in_seconds() -> None:
    from tooltransfer.planner.apps.batch.executors import open_executor

    silent = socket.socket()
    silent.bind(("127.0.0.1", 0))
    silent.listen(8)
    try:
        start = time.perf_counter()
        with pytest.raises(InputError, match="no Dask scheduler answered"):
            with open_executor(scheduler=f"tcp://127.0.0.1:{silent.getsockname()[1]}"):
                pass
        assert time.perf_counter() - start < 10
    finally:
        silent.close()


def test_a_run_whose_every_job_failed_exits_1(tmp_path, capsys) -> None:
    batch = _batch(tmp_path, name="fail", count=1)
    assert main(["batch", "run", str(batch), "--db", str(tmp_path / "f.sqlite"), "--workers", "1", "-q",
                 "--timeout", "0.001"]) == 1
    captured = capsys.readouterr()
    assert "every job of this run failed (timeout 1)" in captured.err
