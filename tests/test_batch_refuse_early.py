"""``batch run`` refuses a store another run writes, or one that holds results without ``--resume``, at once:
before the dataset is read and the skills are learned (issue 29; about 10 s where they are not cached).
A console run with an empty skills cache is refused with exit 2 and leaves the cache empty."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.runner import refuse_taken_store
from tooltransfer.planner.apps.batch.spec import load_batch
from tooltransfer.planner.apps.batch.store import ResultStore, lock_store
from tooltransfer.planner.apps.batch.store_settings import open_batch_store


def _filled(tmp_path: Path, batch: Path) -> Path:
    """A store of ``batch`` holding one result."""
    db = tmp_path / "filled.sqlite"
    with ResultStore(db) as store:
        open_batch_store(store, load_batch(batch), [], resume=False)
        store.put({"task_id": "t-00000", "variant": "mapping/arch", "status": "solved", "finished_at": 0.0})
    return db


def _run(tmp_path: Path, batch: Path, db: Path) -> tuple[subprocess.CompletedProcess, Path]:
    """``tooltransfer batch run`` on ``db`` with an empty skills cache; the run and the cache."""
    cache = tmp_path / "cache"
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "TOOLTRANSFER_CACHE": str(cache)}
    run = subprocess.run([sys.executable, "-m", "tooltransfer.planner.apps.cli", "batch", "run", str(batch), "--db",
                          str(db), "--workers", "1", "-q"], env=env, capture_output=True, text=True, timeout=300,
                         check=False)
    return run, cache


def test_a_store_with_results_is_refused_before_the_skills_are_learned(tmp_path: Path, small_batch) -> None:
    batch = small_batch(count=1)
    db = _filled(tmp_path, batch)
    run, cache = _run(tmp_path, batch, db)
    assert run.returncode == 2, run.stderr
    assert f"--resume: expected --resume to carry on ({db} already holds 1 results)" in run.stderr
    assert "Traceback" not in run.stderr
    assert not cache.exists() or not any(cache.iterdir())  # nothing learned


def test_an_occupied_store_is_refused_before_the_skills_are_learned(tmp_path: Path, small_batch) -> None:
    batch = small_batch(count=1)
    db = tmp_path / "busy.sqlite"
    with lock_store(db):
        run, cache = _run(tmp_path, batch, db)
    assert run.returncode == 2, run.stderr
    assert f"--db {db}:" in run.stderr and f"in use by process {os.getpid()}" in run.stderr
    assert not cache.exists() or not any(cache.iterdir())


def test_the_early_check_leaves_the_rest_to_opening_the_store(tmp_path: Path, small_batch) -> None:
    batch = small_batch(count=1)
    db = _filled(tmp_path, batch)
    refuse_taken_store(db, resume=True)  # carried on
    with pytest.raises(InputError, match="already holds 1 results"):
        refuse_taken_store(db, resume=False)
    refuse_taken_store(tmp_path / "new.sqlite", resume=False)  # a new store
    assert not (tmp_path / "new.sqlite").exists()
    text = tmp_path / "text.sqlite"
    text.write_text("not a database")
    refuse_taken_store(text, resume=False)  # not a store: open_batch_store names it
    assert text.read_text() == "not a database"
