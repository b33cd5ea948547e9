"""The ``tooltransfer`` command runs BLAS on one thread unless the user chose a number (issue 29): checked in
a real console run, whose exit handler asks the OpenBLAS that NumPy loaded how many threads it uses."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tooltransfer.planner.common.blas_threads import PINNED, THREAD_VARIABLES, pin_blas_threads

# run as the console command (main() without arguments) whose command loads NumPy; the exit handler, which
# the command's quick exit runs too, writes whether NumPy was loaded and OpenBLAS's thread count
_RUN = """
import atexit, ctypes, json, sys

OUT = sys.argv[1]

def report():
    libs = sorted({ln.split()[-1] for ln in open("/proc/self/maps") if "openblas" in ln and ".so" in ln})
    names = ("openblas_get_num_threads", "openblas_get_num_threads64_", "scipy_openblas_get_num_threads64_",
             "scipy_openblas_get_num_threads")
    counts = [getattr(ctypes.CDLL(lib), n)() for lib in libs for n in names if hasattr(ctypes.CDLL(lib), n)]
    with open(OUT, "w") as fh:
        json.dump({"numpy": "numpy" in sys.modules, "threads": counts}, fh)

atexit.register(report)
sys.argv = ["tooltransfer", *sys.argv[2:]]
from tooltransfer.planner.apps.cli import main
sys.exit(main())
"""


def _threads(tmp_path: Path, env: dict[str, str], *argv: str) -> list[int]:
    """OpenBLAS's thread counts in a console run of ``tooltransfer argv`` under ``env`` (the user's
    thread variables removed first)."""
    out = tmp_path / "threads.json"
    base = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    run = subprocess.run([sys.executable, "-c", _RUN, str(out), *argv], env={**base, **env}, cwd=tmp_path,
                         capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads(out.read_text())
    assert report["numpy"]  # the command loaded NumPy, so its BLAS read the setting
    if not report["threads"]:
        pytest.skip("NumPy's BLAS here is not an OpenBLAS that says its thread count")
    return report["threads"]


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="finds the loaded OpenBLAS in /proc/self/maps")
def test_the_console_command_runs_blas_on_one_thread_unless_the_user_chose(tmp_path: Path) -> None:
    assert _threads(tmp_path, {}, "schema") == [1]
    cores = len(os.sched_getaffinity(0))
    if cores < 2:
        pytest.skip("one core: OpenBLAS would use one thread anyway")
    assert _threads(tmp_path, {"OPENBLAS_NUM_THREADS": "2"}, "schema") == [2]  # the user's choice kept
    assert _threads(tmp_path, {"OMP_NUM_THREADS": "2"}, "schema") == [2]


def test_pin_sets_the_blas_variables_only_where_the_user_set_none() -> None:
    environ: dict[str, str] = {"PATH": "/bin"}
    assert pin_blas_threads(environ) and environ == {"PATH": "/bin", **PINNED}
    for name in THREAD_VARIABLES:
        chosen = {name: "4"}
        assert not pin_blas_threads(chosen) and chosen == {name: "4"}
    empty = {"OMP_NUM_THREADS": ""}  # set to nothing: no choice
    assert pin_blas_threads(empty) and empty == {"OMP_NUM_THREADS": "", **PINNED}
