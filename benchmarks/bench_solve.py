"""Planner benchmark: `tooltransfer solve problems/paper/transfer_tool2.yaml` as a user runs it.

A new process each time, the skills cached on disk after the first run, the package's bytecode
compiled first (as ``pip install`` leaves it: a checkout whose ``.pyc`` files are stale, e.g. under
``PYTHONDONTWRITEBYTECODE=1``, would compile its sources on every start). Prints the medians of
several runs of the whole process (wall time and CPU time, user + system of the child), of
``tooltransfer --help`` (wall), and of planning alone in-process (:func:`tooltransfer.planner.planning.solve.solve`,
its switch NLPs built each run, as in a new process). Targets: whole-process solve at
most 0.8 s, ``--help`` at most 0.25 s.

``--peer COMMAND...``: another build's solve command (e.g. an older checkout's ``tooltransfer solve
TASK --json``), run interleaved with this one, its medians and the ratio printed beside ours.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import compileall
import re
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TASK = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
NOT_PACKAGE = re.compile(r"[/\\](\.venv[^/\\]*|\.git|build|tests|benchmarks|docs|examples)([/\\]|$)")


def run_child(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, float]:
    """(wall, CPU) seconds of one run of ``cmd`` (CPU: the child's user + system time), in ``env``
    (default: this process's)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=9, help="runs of each command (medians are printed)")
    ap.add_argument("--peer", nargs=argparse.REMAINDER, default=None,
                    help="another build's solve command, run interleaved (the rest of the command line)")
    args = ap.parse_args()
    import tooltransfer

    compileall.compile_dir(Path(tooltransfer.__file__).parent, rx=NOT_PACKAGE, quiet=1)
    exe = Path(sys.executable).with_name("tooltransfer")
    cmds = {"this build": [str(exe), "solve", str(TASK), "--json"]}
    if args.peer:
        cmds["peer"] = list(args.peer)
    for cmd in cmds.values():
        run_child(cmd)  # learn and cache the skills once
    runs: dict[str, list[tuple[float, float]]] = {name: [] for name in cmds}
    helps = []
    for _ in range(args.reps):
        for name, cmd in cmds.items():
            runs[name].append(run_child(cmd))
        helps.append(run_child([str(exe), "--help"])[0])
    med = {name: np.median(np.array(r), axis=0) for name, r in runs.items()}
    for name, (wall, cpu) in med.items():
        print(f"tooltransfer solve, {name} (new process, cached skills): median {wall:.3f} s wall, {cpu:.3f} s CPU "
              f"({args.reps} runs)")
    if "peer" in med:
        print(f"ratio this build / peer: wall {med['this build'][0] / med['peer'][0]:.2f}, "
              f"CPU {med['this build'][1] / med['peer'][1]:.2f}")
    print(f"tooltransfer --help: median {np.median(helps):.3f} s wall")

    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.planner.planning.ss.nlp import clear_cache
    from tooltransfer.problems.task import load_task

    task = load_task(TASK)
    solve(task, TASK)
    plans: list[float] = []
    for _ in range(args.reps):
        clear_cache()  # every run builds its switch NLPs, as a new process does
        t0 = time.perf_counter()
        solve(task, TASK)
        plans.append(time.perf_counter() - t0)
    print(f"planning alone (NLPs built each run): median {np.median(plans):.3f} s")


if __name__ == "__main__":
    main()
