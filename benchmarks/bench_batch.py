"""Batch benchmark: problems/batch/bench_1000.yaml (1,000 generated tasks, OE qp and mapping, SS dmp
and opt: 4,000 plans, no simulation) on 2 cores, through the process pool and through a Dask
LocalCluster of 2 workers on the same batch (targets: at most 10 minutes; Dask within 1.3x of the
pool); then a smaller sample with simulation. Prints wall and CPU times, throughput (plans per
second per core) and the Dask / pool ratio.

On a shared machine the full batch may be too long: ``--count N`` runs the first N tasks (the same
tasks as in the full batch) and extrapolates the 1,000-task wall time linearly, labelled as such.
The two executors run alternately, ``--reps`` times each, and the ratio is of their medians.

    python benchmarks/bench_batch.py                   # the full 1,000 tasks
    python benchmarks/bench_batch.py --count 100 --reps 1 --sim-count 10
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sqlite3
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
BATCH = ROOT / "problems" / "batch" / "bench_1000.yaml"


def _subset(folder: Path, count: int, name: str, **changes: object) -> Path:
    data = yaml.safe_load(BATCH.read_text())
    full = data["count"]
    data.update(count=min(count, full), dataset=str((BATCH.parent / data["dataset"]).resolve()), **changes)
    p = folder / f"{name}.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def _run(batch: Path, db: Path, **kw: object) -> dict[str, float]:
    from tooltransfer.planner.apps.batch.runner import run_batch

    t0, c0 = time.perf_counter(), time.process_time()
    s = run_batch(batch, db, progress=False, **kw)
    wall = time.perf_counter() - t0
    with sqlite3.connect(db) as c:
        cpu = c.execute("SELECT SUM(cpu_time), COUNT(*), SUM(status = 'solved'), SUM(status IN ('error', 'timeout')), "
                        "SUM(wall_time) FROM results").fetchone()
    # busy: the share of the slots' time spent inside jobs (the executor's overhead and idle slots are the rest)
    return {"wall": wall, "run_wall": s.wall, "rows": s.stored, "job_cpu": cpu[0] or 0.0, "solved": cpu[2],
            "failed": cpu[3], "parent_cpu": time.process_time() - c0, "slots": s.slots,
            "busy": (cpu[4] or 0.0) / (s.wall * s.slots) if s.wall > 0 else float("nan"),
            "share": (cpu[0] or 0.0) / cpu[4] if cpu[4] else float("nan")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=1000, help="tasks (the first N of the 1,000)")
    ap.add_argument("--reps", type=int, default=1, help="runs of each executor (alternating)")
    ap.add_argument("--sim-count", type=int, default=20, help="tasks of the simulated sample")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        batch = _subset(folder, args.count, "bench")
        n_var = len(yaml.safe_load(batch.read_text())["variants"]["oe"]) * 2
        pool, dask = [], []
        for rep in range(args.reps):
            pool.append(_run(batch, folder / f"pool{rep}.sqlite", workers=args.workers))
            dask.append(_run(batch, folder / f"dask{rep}.sqlite", dask_local=args.workers))
        for name, runs in (("process pool", pool), ("Dask LocalCluster", dask)):
            r = runs[int(np.argsort([x["wall"] for x in runs])[len(runs) // 2])]
            print(f"{name:>18}: {r['rows']} plans ({args.count} tasks x {n_var} variants) in {r['wall']:.1f} s wall "
                  f"(run {r['run_wall']:.1f} s after the warm-up), {r['solved']} solved, {r['failed']} error/timeout; "
                  f"CPU in the jobs {r['job_cpu']:.1f} s, slots busy {100 * r['busy']:.0f}%, jobs' CPU share "
                  f"{100 * r['share']:.0f}% (other load on the machine lowers it); "
                  f"throughput {r['rows'] / r['run_wall'] / r['slots']:.3f} plans/s per core "
                  f"({r['rows'] / r['run_wall'] / r['slots'] / n_var:.3f} tasks/s per core)")
        pw, dw = float(np.median([x["wall"] for x in pool])), float(np.median([x["wall"] for x in dask]))
        pc = float(np.median([x["job_cpu"] for x in pool]))
        dc = float(np.median([x["job_cpu"] for x in dask]))
        print(f"Dask / pool wall time: {dw / pw:.2f} (target <= 1.3); CPU in the jobs: {dc / pc:.2f} "
              "(a ratio far from 1 means the machine's load changed between the runs)")
        if args.count < 1000:
            per = float(np.median([x["run_wall"] for x in pool])) / args.count
            print(f"EXTRAPOLATED from {args.count} tasks (not measured): 1,000 tasks on the pool ~ "
                  f"{1000 * per / 60:.1f} min (target <= 10 min)")
        else:
            print(f"1,000 tasks on the pool: {pw / 60:.1f} min (target <= 10 min)")
        sim = _subset(folder, args.sim_count, "sim", variants={"oe": ["qp"], "ss": ["opt"]},
                      simulate={"enabled": True, "tolerance": 0.01})
        r = _run(sim, folder / "sim.sqlite", workers=args.workers)
        with sqlite3.connect(folder / "sim.sqlite") as c:
            n_sim, ok, med, sim_t = c.execute("SELECT COUNT(sim_success), SUM(sim_success), AVG(sim_final_error), "
                                              "AVG(sim_wall_time) FROM results").fetchone()
        print(f"with simulation ({args.sim_count} tasks, qp/opt): {r['wall']:.1f} s wall, {r['solved']} solved, "
              f"{n_sim} simulated, {ok or 0} within 10 mm of the target (mean final error "
              f"{1e3 * (med or float('nan')):.1f} mm), {sim_t or float('nan'):.2f} s of simulation per plan; "
              f"throughput {r['rows'] / r['run_wall'] / r['slots']:.3f} tasks/s per core")


if __name__ == "__main__":
    main()
