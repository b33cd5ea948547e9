"""Test-wide settings: learned skills are cached in a temporary folder, not in the user's home; the
certificate looks remembered per process emptied before each test; a factory of small batch files."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]

# the helpers' checks report their values on failure as a test's own asserts do
pytest.register_assert_rewrite("guided_ladder")


@pytest.fixture(autouse=True, scope="session")
def _skill_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    mp = pytest.MonkeyPatch()
    if os.environ.get("PYTEST_XDIST_WORKER"):  # one cache for the run's workers (its files are written atomically)
        cache = tmp_path_factory.getbasetemp().parent / "skill_cache"
        cache.mkdir(exist_ok=True)
    else:
        cache = tmp_path_factory.mktemp("skill_cache")
    mp.setenv("TOOLTRANSFER_CACHE", str(cache))
    yield
    mp.undo()


@pytest.fixture(autouse=True)
def _fresh_certificate_looks() -> None:
    """Each test looks for its certificates afresh (the verdict's per-process memo, verdicts/decide.py, emptied):
    a test that changes a certificate's settings cannot leave a look behind for the next."""
    from tooltransfer.planner.planning.verdicts import decide

    decide._LOOKS.clear()


@pytest.fixture
def small_batch(tmp_path: Path) -> Callable[..., Path]:
    """``make(name="t", count=3, oe=("mapping",), ss=("arch",), **fields)``: a batch file in ``tmp_path``,
    problems/batch/small.yaml on the committed finger dataset with these fields."""

    def make(name: str = "t", count: int = 3, oe: tuple[str, ...] = ("mapping",), ss: tuple[str, ...] = ("arch",),
             **fields: Any) -> Path:
        data = yaml.safe_load((ROOT / "problems" / "batch" / "small.yaml").read_text())
        data.update(name=name, count=count, dataset=str(ROOT / "problems" / "data" / "finger_demos"),
                    variants={"oe": list(oe), "ss": list(ss)}, **fields)
        path = tmp_path / f"{name}.yaml"
        path.write_text(yaml.safe_dump(data))
        return path

    return make


@pytest.fixture(scope="session")
def transfer_plan_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The paper's transfer task (problems/paper/transfer_tool2.yaml) solved once and written as a plan file."""
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task

    task = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
    plan = solve(load_task(task), task)
    assert plan.status == "solved", plan.reason
    return plan.write(tmp_path_factory.mktemp("transfer") / "plan.json")
