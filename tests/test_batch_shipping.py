"""The learned skills travel with the batch (tooltransfer.planner.apps.batch.shipping): Dask workers started in another
working directory, on a machine where the batch's dataset does not exist, run a batch to completion;
workers that join later get the skills too; the process pool reads one file the run removes; a job
whose skills are not on its worker becomes an error row naming it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from tooltransfer.planner.apps.batch import shipping
from tooltransfer.planner.apps.batch.executors import open_executor
from tooltransfer.planner.apps.batch.runner import run_batch
from tooltransfer.planner.apps.batch.store import ResultStore
from tooltransfer.planner.apps.batch.worker import Job, run_job

ROOT = Path(__file__).resolve().parents[1]
DATASET = ROOT / "problems" / "data" / "finger_demos"


def _batch(folder: Path, dataset: Path, count: int = 3, **extra) -> Path:
    """Tasks that all solve with qp/arch: the finger tool, short pushes, no obstacles."""
    data = yaml.safe_load((ROOT / "problems" / "batch" / "small.yaml").read_text())
    data.update({"name": "ship", "count": count, "tools": ["finger"], "dataset": str(dataset),
                 "distance": [0.03, 0.06], "obstacles": {"count": [0, 0]}, "variants": {"oe": ["qp"], "ss": ["arch"]},
                 **extra})
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / "ship.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def _skills(tmp_path: Path) -> shipping.ShippedSkills:
    from tooltransfer.planner.apps.batch.generate import generate_task
    from tooltransfer.planner.apps.batch.spec import load_batch

    batch = _batch(tmp_path / "b", DATASET, count=1)
    spec = load_batch(batch)
    return shipping.batch_skills(spec, batch, generate_task(spec, 0, str(DATASET)))


def test_workers_in_another_folder_without_the_dataset_run_the_batch(tmp_path, monkeypatch) -> None:
    """Two `dask worker` processes started from their own folders (their own local directory and an empty
    skills cache) against a scheduler: the dataset, copied for this run, is deleted as soon as the skills
    are learned, so neither the workers nor their sandboxes can read it, and every task still solves and
    is executed open and closed loop (the closed loop re-plans with the shipped skills too)."""
    from distributed import Client, LocalCluster

    start = time.perf_counter()
    dataset = tmp_path / "here" / "finger_demos"
    shutil.copytree(DATASET, dataset)
    batch = _batch(tmp_path / "here", dataset, count=3)
    learn = shipping.batch_skills

    def learn_then_delete(*args, **kwargs):
        skills = learn(*args, **kwargs)
        shutil.rmtree(dataset)  # from here on the dataset exists nowhere
        return skills

    monkeypatch.setattr(shipping, "batch_skills", learn_then_delete)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "TOOLTRANSFER_CACHE": str(tmp_path / "worker_cache")}
    workers: list[subprocess.Popen] = []
    with LocalCluster(n_workers=0, dashboard_address=None, protocol="tcp", host="127.0.0.1") as cluster:
        addr = cluster.scheduler_address
        try:
            for i in range(2):
                away = tmp_path / f"away{i}"
                away.mkdir()
                workers.append(subprocess.Popen(
                    [sys.executable, "-m", "dask", "worker", addr, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                     "--local-directory", str(away / "scratch")],
                    cwd=away, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            with Client(addr) as client:
                client.wait_for_workers(2, timeout=60)
                # (functions of the standard library: the workers cannot import this test module)
                assert sorted(client.run(os.getcwd).values()) == [str(tmp_path / "away0"), str(tmp_path / "away1")]
                assert all(client.run(os.path.isdir, str(dataset)).values())  # one machine: until learned
                summary = run_batch(batch, tmp_path / "ship.sqlite", scheduler=addr, simulate=True, progress=False)
                assert not dataset.exists()
                assert not any(client.run(os.path.exists, str(dataset)).values())
                # the run unregistered its plugin: the workers' copies are gone with it
                assert not list(tmp_path.glob("away*/scratch/**/tooltransfer-skills-*.json"))
        finally:
            for w in workers:
                w.kill()
                w.wait(timeout=10)
    with ResultStore(tmp_path / "ship.sqlite") as store:
        rows = store.rows()
    assert (summary.kind, summary.stored, summary.slots) == ("dask", 3, 2)
    assert [r["status"] for r in rows] == ["solved"] * 3, [r["reason"] for r in rows]
    assert {r["worker"].rsplit(":", 1)[1] for r in rows} <= {str(w.pid) for w in workers}
    assert all(r["open_loop_status"] == "done" for r in rows), [r["open_loop_reason"] for r in rows]
    assert all(r["closed_loop_status"] in ("reached", "closest", "rounds") for r in rows), \
        [r["closed_loop_reason"] for r in rows]
    print(f"3 tasks on 2 workers without the dataset, planned and executed: {time.perf_counter() - start:.1f} s")


def test_workers_that_join_later_get_the_skills_and_jobs_and_the_run_removes_them(tmp_path, monkeypatch) -> None:
    from distributed import Client, LocalCluster

    from tooltransfer.planner.apps.batch import dask_plugin

    skills = _skills(tmp_path)
    monkeypatch.setattr(dask_plugin, "RECOUNT", 0.0)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with open_executor(scheduler=cluster.scheduler_address) as slots:
            slots.ship(skills)
            assert slots.current() == 1
            cluster.scale(2)  # a worker that joins after the run started (dask-jobqueue's adapt, a scaled-up pod group)
            client = slots.client
            assert isinstance(client, Client)
            client.wait_for_workers(2, timeout=60)
            assert slots.current() == 2  # the runner's window widens: the new worker gets jobs
            paths = client.run(shipping.local_path, skills.digest)
            assert len(paths) == 2 and all(paths.values()) and len(set(paths.values())) == 2
            for p in paths.values():
                assert Path(p).read_text() == skills.text
        assert not any(Path(p).exists() for p in paths.values())


def test_every_worker_of_a_larger_cluster_is_probed_and_counted() -> None:
    """More than five workers: distributed's scheduler_info listed only five by default for a while."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=7, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        with open_executor(scheduler=cluster.scheduler_address) as slots:
            assert slots.slots == 7 and slots.where.startswith("7 workers")


def test_the_pool_reads_one_file_the_run_removes(tmp_path) -> None:
    skills = _skills(tmp_path)
    with open_executor(workers=1) as slots:
        slots.ship(skills)
        path = slots.executor.submit(shipping.local_path, skills.digest).result(timeout=60)
        assert path is not None and Path(path).read_text() == skills.text
    assert not Path(path).exists()
    assert shipping.local_path(skills.digest) is None


def test_a_job_whose_skills_are_not_on_its_worker_is_an_error_row_naming_it() -> None:
    row = run_job(Job("t", "qp/arch", args=({"skills": {"dataset": "/nowhere"}},), skills="0123456789abcdef"))
    assert row["status"] == "error"
    assert "skills (0123456789abcdef) were not shipped to this worker" in row["reason"]
    assert f":{os.getpid()})" in row["reason"]


def test_localize_replaces_only_a_task_s_skills() -> None:
    task = {"name": "t", "skills": {"dataset": "/data/demos"}}
    assert shipping.localize((task, "src", "qp"), "/tmp/s.json") == \
        ({"name": "t", "skills": {"file": "/tmp/s.json"}}, "src", "qp")
    assert task["skills"] == {"dataset": "/data/demos"}  # not changed in place
    assert shipping.localize((b"plan", 0.01), "/tmp/s.json") == (b"plan", 0.01)
    assert shipping.localize(({"status": "error"},), "/tmp/s.json") == ({"status": "error"},)


@pytest.mark.parametrize("ss", ["arch", "dmp"])
def test_a_dataset_that_cannot_be_shipped(tmp_path, monkeypatch, ss: str) -> None:
    """Demonstrations that never switch faces have no SS skill, so no skills file: with arch switches only the
    run goes on the old way (None: the workers read the dataset), a variant that needs the SS skill is refused."""
    from tooltransfer.errors import InputError
    from tooltransfer.planner.apps.batch.generate import generate_task
    from tooltransfer.planner.apps.batch.spec import load_batch

    batch = _batch(tmp_path / "b", DATASET, count=1, variants={"oe": ["qp"], "ss": [ss]})
    spec = load_batch(batch)
    first = generate_task(spec, 0, str(DATASET))

    def no_switches(*args, **kwargs):
        raise InputError("skills.dataset", "a dataset whose demonstrations switch faces at least once", "x")

    monkeypatch.setattr("tooltransfer.planner.learning.skills.learn_skills", no_switches)
    if ss == "arch":
        assert shipping.batch_skills(spec, batch, first) is None
    else:
        with pytest.raises(InputError, match="switch faces"):
            shipping.batch_skills(spec, batch, first)
