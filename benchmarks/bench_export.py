"""Quick-command benchmark: `tooltransfer export PLAN --format csv` on the transfer plan, as a user runs it.

A new process each time, the package's bytecode compiled first (as ``pip install`` leaves it). The
plan is solved once (``problems/paper/transfer_tool2.yaml``, skills cached). Prints the medians of the
whole process's wall time and CPU time (user + system of the child) over ``--reps`` runs; target:
0.5 s wall. ``--peer-path DIR``: a folder holding another build's ``tooltransfer`` package (for
instance ``git archive main`` unpacked into ``DIR/tooltransfer``), run interleaved with this one on
the same plan through ``PYTHONPATH``, its medians and the ratio printed beside ours.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import compileall
import sys
import tempfile
from pathlib import Path

import numpy as np
from bench_solve import NOT_PACKAGE, TASK, run_child


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=11, help="runs of each command (medians are printed)")
    ap.add_argument("--peer-path", type=Path, default=None, help="folder holding another build's tooltransfer")
    args = ap.parse_args()
    import tooltransfer
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task

    compileall.compile_dir(Path(tooltransfer.__file__).parent, rx=NOT_PACKAGE, quiet=1)
    out = Path(tempfile.mkdtemp(prefix="bench_export_"))
    plan = solve(load_task(TASK), TASK).write(out / "plan.json")
    cmd = [sys.executable, "-m", "tooltransfer.planner.apps.cli", "export", str(plan), "--format", "csv",
           "-o", str(out / "plan.csv")]
    envs = {"this build": None}
    if args.peer_path:
        compileall.compile_dir(args.peer_path / "tooltransfer", rx=NOT_PACKAGE, quiet=1)
        envs["peer"] = {**os.environ, "PYTHONPATH": str(args.peer_path)}
    runs: dict[str, list[tuple[float, float]]] = {name: [] for name in envs}
    for _ in range(args.reps):
        for name, env in envs.items():
            runs[name].append(run_child(cmd, env))
    med = {name: np.median(np.array(r), axis=0) for name, r in runs.items()}
    for name, (wall, cpu) in med.items():
        print(f"tooltransfer export --format csv, {name}: median {wall:.3f} s wall, {cpu:.3f} s CPU ({args.reps} runs)")
    if "peer" in med:
        print(f"ratio this build / peer: wall {med['this build'][0] / med['peer'][0]:.2f}, "
              f"CPU {med['this build'][1] / med['peer'][1]:.2f}")


if __name__ == "__main__":
    main()
