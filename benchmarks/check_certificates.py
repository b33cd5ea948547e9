"""Every certificate of a verdict run against an independent search: a feasible task called infeasible
is the worst defect a verdict can have, so each one is checked by code the planner does not use.

Run after the verdict benchmark (``make bench-verdicts`` or ``python benchmarks/bench_verdicts.py --json
RESULTS``)::

    python benchmarks/check_certificates.py RESULTS.json [--budget 15000] [--workers 2]

For every task the run called ``infeasible`` (whatever the certificate's kind) the task is generated
again from its batch file and the test suite's own lattice search
(``tests/test_verdicts.py::lattice_search``: straight pushes of 3 mm in five directions across each
face's whole friction cone cut by its tool-file cone, from every tool yaw at which the Omni holds the
face with the contact anywhere on its range, the puck kept its clearance from the obstacles; breadth
first, one visit per 1.5 mm cell) looks for the target. It is looser than the planner's rules where
it matters for soundness (no tool body, no contact rolling, no switches: any face at any node) and
coarser where it cannot be exact (its steps and cells), so it proves nothing either way; what it
shows is how close a search that ignores half the rules comes. The report lists each task's closest
approach [mm] and flags those within ``--flag`` (3 mm, the test suite's threshold); the exit code is 1
when any is flagged. Single-threaded BLAS; CPU seconds per task are printed.

With ``--unknowns`` the same search runs on the tasks the run left ``unknown`` instead, and the report
counts how many of them it comes within ``--flag`` of: what the unknowns are made of. Reached by a
search that ignores the contact's rolling, the tool's sweep and the switches, an unknown is likely
feasible with plans this planner's own narrower rules do not make (the contact at a face's tip, pushes
at the very edge of the cone); not reached, it is a candidate for a tighter certificate. Nothing is
flagged as an error in this mode (exit code 0): an unknown is allowed to be either.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import json
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "benchmarks"), str(ROOT / "tests")]

from bench_execution import _task  # noqa: E402
from bench_verdicts import make_verdict_jobs  # noqa: E402


def _closest(args: tuple[Any, int]) -> tuple[str, float, float]:
    """``(task_id, closest approach [m], CPU [s])`` of the lattice search on one job's task."""
    import numpy as np
    from test_verdicts import _rules_of, lattice_search

    job, budget = args
    task = _task(job)
    setting, _ = _rules_of(task)
    cpu = time.process_time()
    d = lattice_search(setting, np.array(task.start), np.array(task.target), budget=budget)
    return job.task_id, d, time.process_time() - cpu


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a bench_verdicts.py --json file")
    ap.add_argument("--budget", type=int, default=15000, help="the lattice search's expansions per task")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--flag", type=float, default=0.003, help="flag a task the search comes this close to [m]")
    ap.add_argument("--unknowns", action="store_true",
                    help="search on the tasks left unknown instead (a description, not a check)")
    args = ap.parse_args(argv)
    data = json.loads(args.results.read_text())
    verdict = "unknown" if args.unknowns else "infeasible"
    rows = [r for r in data["rows"] if r.get("verdict") == verdict]
    # the run's batch files, else the files of that name in this checkout (a run made elsewhere)
    batches = [Path(b) if Path(b).is_file() else ROOT / "problems" / "batch" / Path(b).name
               for b in data["meta"]["batches"]]
    jobs = {j.task_id: j for j in make_verdict_jobs(batches, data["meta"].get("count"), 600.0, False)}
    missing = [r["task_id"] for r in rows if r["task_id"] not in jobs]
    if missing:
        print(f"{args.results}: rows not in the run's batch files: {missing}", file=sys.stderr)
        return 2
    kind = {r["task_id"]: r.get("evidence_kind") for r in rows}
    found: list[tuple[str, float, float]] = []
    with ProcessPoolExecutor(args.workers) as pool:
        for tid, d, cpu in pool.map(_closest, [(jobs[r["task_id"]], args.budget) for r in rows]):
            found.append((tid, d, cpu))
            mark = ("  reached" if args.unknowns else "  FLAGGED") if d <= args.flag else ""
            print(f"{tid} {kind[tid] or verdict}: closest {d * 1e3:.2f} mm (CPU {cpu:.1f} s){mark}", flush=True)
    if not found:
        print(f"no {'unknown' if args.unknowns else 'certificate'} in the run")
        return 0
    flagged = [t for t, d, _ in found if d <= args.flag]
    if args.unknowns:
        print(f"\n{len(found)} unknowns; the lattice search (no rolling, no tool sweep, no switches) comes within "
              f"{args.flag * 1e3:g} mm of the target on {len(flagged)}; not on {len(found) - len(flagged)}: "
              f"{[t for t, d, _ in found if d > args.flag]}")
        return 0
    print(f"\n{len(found)} certificates; the lattice search's closest approach: min "
          f"{min(d for _, d, _ in found) * 1e3:.2f} mm; within {args.flag * 1e3:g} mm: {len(flagged)} {flagged}")
    return 1 if flagged else 0


if __name__ == "__main__":
    sys.exit(main())
