"""Planner benchmark: `tooltransfer solve problems/paper/transfer_tool2.yaml` as a user runs it
(a new process each time, skills cached on disk after the first run), median wall time of several
runs including Python start-up (target 1.5 s), and planning alone in-process (target 0.5 s)."""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import subprocess
import sys
import time
from pathlib import Path

import numpy as np

TASK = Path(__file__).resolve().parents[1] / "problems" / "paper" / "transfer_tool2.yaml"


def main(reps: int = 5) -> None:
    exe = Path(sys.executable).with_name("tooltransfer")
    cmd = [str(exe), "solve", str(TASK), "--json"]
    subprocess.run(cmd, check=True, capture_output=True)  # learn and cache the skills once
    walls = []
    for _ in range(reps):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        walls.append(time.perf_counter() - t0)
    from tooltransfer.planner.solve import solve
    from tooltransfer.problems.task import load_task

    task = load_task(TASK)
    solve(task, TASK)
    plans = []
    for _ in range(reps):
        t0 = time.perf_counter()
        solve(task, TASK)
        plans.append(time.perf_counter() - t0)
    print(f"tooltransfer solve (new process, cached skills): median {np.median(walls):.2f} s wall; "
          f"planning alone: median {np.median(plans):.3f} s")


if __name__ == "__main__":
    main()
