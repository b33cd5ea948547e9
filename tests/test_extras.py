"""Optional extras (issue 18): the core (learn, solve, export, schema, tasks) runs without mujoco,
matplotlib and dask; a command that needs one of them ends in exit 2 with one line naming the extra
to install. The optional modules are blocked in a fresh interpreter (``sys.modules[name] = None``)."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TASK = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
BLOCK = ("mujoco", "matplotlib", "PIL", "dask", "distributed")


def _cli(tmp: Path, *argv: str) -> subprocess.CompletedProcess:
    code = ("import sys\n"
            f"for name in {BLOCK!r}:\n    sys.modules[name] = None\n"
            "from tooltransfer.planner.apps.cli import main\n"
            f"sys.exit(main({list(argv)!r}))\n")
    return subprocess.run([sys.executable, "-c", code], cwd=tmp, capture_output=True, text=True, timeout=600,
                          check=False)


def test_the_extras_hold_what_the_core_does_not_need() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    core = " ".join(project["dependencies"])
    assert not any(name in core for name in ("mujoco", "matplotlib", "dask", "distributed"))
    extras = project["optional-dependencies"]
    assert {"sim", "plots", "dask", "all"} <= set(extras)
    assert "tooltransfer[all]" in extras["test"]  # make test runs everything


def test_the_core_runs_without_the_extras(tmp_path: Path) -> None:
    run = _cli(tmp_path, "solve", str(TASK), "-o", "plan.json")
    assert run.returncode == 0, run.stderr[-2000:]
    data = str(ROOT / "problems" / "data" / "finger_demos")
    for argv in (("export", "plan.json", "--format", "csv", "-o", "plan.csv"), ("schema",), ("tasks",),
                 ("learn", data, "-o", "skills.json"), ("segment", data)):
        run = _cli(tmp_path, *argv)
        assert run.returncode == 0, (argv, run.stderr[-2000:])
    assert (tmp_path / "plan.csv").stat().st_size > 1000


@pytest.mark.parametrize(("argv", "extra"), [
    (("simulate", "plan.json"), "sim"),
    (("tools", "--out", "tools.png"), "plots"),
])
def test_a_command_that_needs_an_extra_names_it(tmp_path: Path, argv: tuple[str, ...], extra: str) -> None:
    assert _cli(tmp_path, "solve", str(TASK), "-o", "plan.json").returncode == 0
    run = _cli(tmp_path, *argv)
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr[-2000:]
    assert f"pip install 'tooltransfer[{extra}]'" in lines[0] and "Traceback" not in run.stderr
