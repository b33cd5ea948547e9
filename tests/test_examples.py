"""Every script in examples/ runs as a user would run it (a subprocess, small settings) and does what
its docstring says."""

from __future__ import annotations

import csv
import os
import re
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
TIMEOUT = 180  # [s] per script; each takes 5-20 s on 2 cores


def run(script: str, *args: str, cwd: Path) -> str:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, str(EXAMPLES / script), *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=TIMEOUT)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    print(f"{script}: {time.perf_counter() - start:.1f} s")
    return proc.stdout


def test_every_example_is_tested() -> None:
    scripts = {p.name for p in EXAMPLES.glob("*.py")}
    tested = set(re.findall(r'run\("(\w+\.py)"', Path(__file__).read_text()))
    assert scripts == tested, scripts ^ tested


@pytest.mark.parametrize("script", sorted(p.name for p in EXAMPLES.glob("*.py")))
def test_example_help(script: str, tmp_path: Path) -> None:
    proc = subprocess.run([sys.executable, str(EXAMPLES / script), "--help"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and "usage:" in proc.stdout, proc.stderr


def test_learn_from_recordings(tmp_path: Path) -> None:
    from tooltransfer.planner.learning.skills import Skills

    out = run("learn_from_recordings.py", "--convert", str(tmp_path / "my_dataset"),
              "-o", str(tmp_path / "skills.json"), cwd=tmp_path)
    assert (tmp_path / "my_dataset" / "meta.yaml").is_file()
    assert "3 demonstrations with tool 'finger'" in out and "push mechanics: mu" in out
    skills = Skills.load(tmp_path / "skills.json")
    assert skills.mechanics is not None and skills.ss is not None
    assert Path(skills.dataset).resolve() == (tmp_path / "my_dataset").resolve()


def test_plan_with_a_new_tool(tmp_path: Path) -> None:
    from tooltransfer.planner.planning.plan import read_plan
    from tooltransfer.problems.task import load_task

    out = run("plan_with_a_new_tool.py", "--out", str(tmp_path), "--plot", cwd=tmp_path)
    assert "solved" in out
    task = load_task(tmp_path / "task.yaml")                # the written task stands alone
    assert task.tool.name == "spatula"
    plan = read_plan(tmp_path / "plan.json")
    assert plan.status == "solved" and {p.faces[0] for p in plan.pushes} <= {"front", "left"}
    assert (tmp_path / "plan.png").stat().st_size > 10_000


def test_compare_variants(tmp_path: Path) -> None:
    out = run("compare_variants.py", "--simulate", "--csv", str(tmp_path / "compare.csv"), cwd=tmp_path)
    assert "qp/opt" in out and "mapping/opt" in out and "open-loop error" in out
    with (tmp_path / "compare.csv").open() as fh:
        rows = {r["variant"]: r for r in csv.DictReader(fh)}
    assert set(rows) == {"qp/opt", "mapping/opt"}
    assert rows["qp/opt"]["status"] == "solved" and float(rows["qp/opt"]["open_loop_error"]) < 0.005
    assert rows["mapping/opt"]["status"] in ("solved", "infeasible", "unknown")


def test_batch_on_a_cluster(tmp_path: Path) -> None:
    out = run("batch_on_a_cluster.py", "--out", str(tmp_path), cwd=tmp_path)
    assert "local Dask cluster: 2 workers" in out and "on 2 dask slots" in out
    with sqlite3.connect(tmp_path / "results.sqlite") as db:
        statuses = [r[0] for r in db.execute("select status from results")]
    assert len(statuses) == 4 and set(statuses) <= {"solved", "infeasible", "unknown"}
    assert (tmp_path / "report" / "summary.csv").is_file()


def test_closed_loop_mismatched_plant(tmp_path: Path) -> None:
    out = run("closed_loop_mismatched_plant.py", cwd=tmp_path)
    open_mm = float(re.search(r"open loop: +object +([\d.]+) mm", out)[1])
    closed = re.search(r"closed loop: object +([\d.]+) mm from the target, (\w+)", out)
    assert closed and closed[2] in ("reached", "closest", "rounds"), out
    assert float(closed[1]) <= 3.0 and float(closed[1]) < open_mm, out
