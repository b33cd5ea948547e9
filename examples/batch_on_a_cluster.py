"""Run a batch feasibility study on a Dask cluster and report it.

By default the script starts a :class:`distributed.LocalCluster` of two worker processes and hands
its scheduler's address to the batch runner, exactly as a remote cluster would be used; with
``--scheduler tcp://HOST:8786`` it uses a cluster you started yourself (``dask scheduler`` and
``dask worker`` on the machines, or dask-jobqueue on SLURM, below) and starts nothing.

    python examples/batch_on_a_cluster.py                                  # examples/tiny_batch.yaml, 2 local workers
    python examples/batch_on_a_cluster.py problems/batch/small.yaml --workers 4 --out out/small
    python examples/batch_on_a_cluster.py --scheduler tcp://head-node:8786 --resume

Each (task, variant) pair runs in a sandbox process on a worker with the batch file's timeout, and
every result is committed to the SQLite store as it arrives, so a run that is stopped resumes with
``--resume`` without recomputing anything. The report (success rates with Wilson intervals, reasons
of failure, times) is printed and written as CSV files and figures.

On SLURM the cluster comes from dask-jobqueue (``pip install dask-jobqueue``; not a dependency of
this package), e.g.::

    from dask_jobqueue import SLURMCluster
    cluster = SLURMCluster(cores=1, processes=1, memory="2GB", walltime="01:00:00")
    cluster.scale(jobs=16)
    run_batch(batch, db, scheduler=cluster.scheduler_address)

Workers of a remote cluster run the planner themselves: they need this package installed (the same
version) and the batch's dataset at the same absolute path as on the machine that submits.
"""

from __future__ import annotations

import argparse
import logging
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("batch", nargs="?", type=Path, default=HERE / "tiny_batch.yaml", help="batch file")
    ap.add_argument("--out", type=Path, default=Path("out/examples/batch"), help="store and report folder")
    ap.add_argument("--workers", type=int, default=2, help="local cluster: worker processes")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler (starts no local cluster)")
    ap.add_argument("--resume", action="store_true", help="carry on the store, skipping stored results")
    ap.add_argument("--simulate", action="store_true", help="also execute every solved plan, open and closed loop")
    args = ap.parse_args(argv)

    from tooltransfer.planner.apps.batch.report import write_report
    from tooltransfer.planner.apps.batch.runner import run_batch

    args.out.mkdir(parents=True, exist_ok=True)
    db = args.out / "results.sqlite"
    if not args.resume:
        for p in args.out.glob("results.sqlite*"):
            p.unlink()

    def run(address: str) -> None:
        start = time.perf_counter()
        summary = run_batch(args.batch, db, scheduler=address, resume=args.resume,
                            simulate=True if args.simulate else None, progress=False)
        print(f"{summary.stored} results stored ({dict(summary.counts)}), {summary.skipped} already there, "
              f"on {summary.slots} {summary.kind} slots in {time.perf_counter() - start:.1f} s")

    if args.scheduler is not None:
        run(args.scheduler)
    else:
        from distributed import LocalCluster

        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=logging.ERROR) as cluster:
            print(f"local Dask cluster: {args.workers} workers, scheduler at {cluster.scheduler_address}")
            run(cluster.scheduler_address)

    written = write_report(db, args.out / "report")
    print(f"wrote {db} and " + ", ".join(p.name for p in written) + f" to {args.out / 'report'}/")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
