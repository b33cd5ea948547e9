"""``tooltransfer batch generate|run|report``: batch feasibility studies from the command line.

Exit codes: 0 done, 1 every job this run ran failed (``error`` or ``timeout``: e.g. Dask workers that
cannot run them), 4 some of the rows this run stored are ``error`` rows (a job raised or its sandbox
died: ``batch report`` gives the reasons, ``--resume --retry error`` runs them again), 2 bad input
(a message naming the field: a corrupt dataset, a store another run is writing or another program's
file, a full disk or a damaged store, workers without the package), 130 stopped by Ctrl-C (the store
can be resumed with ``--resume``). ``batch generate`` writes at most :data:`MAX_TASK_FILES` task files (``--first N``
writes the first N of a larger batch).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from tooltransfer.planner.apps.batch.runner import RunSummary

EXIT_INTERRUPTED = 130
EXIT_ALL_FAILED = 1
EXIT_ERRORS = 4
#: Most task files ``batch generate`` writes in one go (a batch may hold a million tasks: ``batch run``
#: generates them as it runs; ``--first N`` writes the first N).
MAX_TASK_FILES = 100_000


def _cmd_generate(args: argparse.Namespace) -> int:
    from tooltransfer.errors import InputError
    from tooltransfer.planner.apps.batch.generate import write_tasks
    from tooltransfer.planner.apps.batch.spec import load_batch

    spec = load_batch(args.batch)
    n = spec.count if args.first is None else args.first
    if args.first is not None and not 1 <= args.first <= spec.count:
        raise InputError("--first", f"a number of tasks in [1, count = {spec.count}]", args.first)
    if n > MAX_TASK_FILES:
        raise InputError(f"{args.batch}: count", f"at most {MAX_TASK_FILES} task files to write (--first N writes "
                         "the first N; `batch run` generates every task as it runs)", spec.count)
    if n < spec.count:
        spec = spec.model_copy(update={"count": n})  # task i does not depend on count
    paths = write_tasks(spec, args.batch, args.out)
    print(f"wrote {len(paths)} task files to {args.out}/ (each one solves on its own: tooltransfer solve FILE)")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.batch.runner import run_batch

    retry = tuple(s for s in (args.retry or "").split(",") if s)
    bad = [s for s in retry if s not in ("error", "timeout", "infeasible", "unknown", "violated")]
    if bad:
        from tooltransfer.errors import InputError

        raise InputError("--retry", "a comma-separated list of error, timeout, infeasible, unknown, violated", bad[0])
    s = run_batch(args.batch, args.db, workers=args.workers, scheduler=args.scheduler, dask_local=args.dask_local,
                  timeout=args.timeout, simulate=args.simulate, resume=args.resume, retry=retry,
                  progress=not args.quiet, budget=args.budget)
    counts = ", ".join(f"{k} {v}" for k, v in sorted(s.counts.items())) or "nothing to do"
    print(f"{s.stored} results stored ({counts}), {s.skipped} already done, of {s.total}; "
          f"{s.wall:.1f} s on {s.slots} {s.kind} slots: {s.throughput:.3f} results (task-variant pairs) per second "
          "per slot")
    if s.kept:
        print(f"{s.kept} of them ran again and gave no verdict (error or timeout): the verdicts stored before were "
              "kept instead, their rows' detail says how the new run ended")
    code = run_exit_code(s)
    if code == EXIT_INTERRUPTED:
        print(f"stopped before the end: carry on with `tooltransfer batch run {args.batch} --db {args.db} --resume`")
    elif code == EXIT_ALL_FAILED:
        print(f"tooltransfer: error: every job of this run failed ({counts}): see `tooltransfer batch report "
              f"{args.db}` for the reasons", file=sys.stderr)
    elif code == EXIT_ERRORS:
        print(f"tooltransfer: error: {s.counts['error']} jobs of this run ended in error: see `tooltransfer batch "
              f"report {args.db}` for the reasons, `--resume --retry error` runs them again", file=sys.stderr)
    return code


def run_exit_code(s: RunSummary) -> int:
    """The exit code of a ``batch run`` that did what ``s`` says (module docstring): 130 stopped by
    Ctrl-C, 1 every row it stored ``error`` or ``timeout``, 4 some ``error`` rows, else 0."""
    if s.interrupted:
        return EXIT_INTERRUPTED
    if s.stored and set(s.counts) <= {"error", "timeout"}:
        return EXIT_ALL_FAILED
    if s.counts.get("error"):
        return EXIT_ERRORS
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.batch.report import write_report

    written = write_report(args.db, args.out)
    if written:
        print(f"wrote {', '.join(p.name for p in written)} to {args.out}/")
    return 0


def _cmd_schema(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.batch.spec import batch_json_schema

    print(batch_json_schema())
    return 0


def add_batch_parser(sub: argparse._SubParsersAction,
                     add: Callable[..., argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """Register ``batch`` and its commands; ``add(sub, name, help, example, func)`` makes a command."""
    group = sub.add_parser("batch", help="batch feasibility studies: generate tasks, run them, report",
                           description="batch feasibility studies: generate tasks from a batch file, run every "
                           "task with every variant in parallel (process pool or Dask) into a resumable SQLite "
                           "store, report success rates, times and violations")
    bsub = group.add_subparsers(dest="batch_command", required=True)
    p = add(bsub, "generate", "write the batch's tasks as task files (each one valid on its own)",
            "tooltransfer batch generate problems/batch/small.yaml --out out/small_tasks", _cmd_generate)
    p.add_argument("batch", type=Path, help="batch file (YAML)")
    p.add_argument("--out", type=Path, required=True, help="folder for the task files")
    p.add_argument("--first", type=int, default=None, metavar="N",
                   help=f"write only the first N tasks (at most {MAX_TASK_FILES} files are written in one go)")
    p = add(bsub, "run", "run every task of a batch with every variant, storing each result as it finishes",
            "tooltransfer batch run problems/batch/small.yaml --db out/small.sqlite --workers 2 --simulate\n"
            "  tooltransfer batch run problems/batch/small.yaml --db out/small.sqlite --dask-local 2 --resume\n"
            "  tooltransfer batch run problems/batch/small.yaml --db out/small.sqlite --scheduler tcp://host:8786",
            _cmd_run)
    p.add_argument("batch", type=Path, help="batch file (YAML)")
    p.add_argument("--db", type=Path, required=True, help="SQLite results file (created if missing)")
    p.add_argument("--workers", type=int, default=None, help="process-pool size (default: the CPU count)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", default=None, help="address of a running Dask scheduler")
    where.add_argument("--dask-local", type=int, default=None, metavar="N", help="start a local Dask cluster of N "
                       "worker processes")
    p.add_argument("--timeout", type=float, default=None, help="per task and variant [s] (default: the batch file's)")
    p.add_argument("--simulate", action=argparse.BooleanOptionalAction, default=None,
                   help="execute every solved plan on the simulated platform open loop and closed loop (default: the "
                   "batch file's simulate.enabled); part of the store's settings: a resume with the other setting is "
                   "refused")
    p.add_argument("--resume", action="store_true", help="carry on a store of this batch, skipping stored results")
    p.add_argument("--retry", default=None, metavar="STATUSES",
                   help="with --resume, run these statuses again (comma-separated: error,timeout,infeasible,"
                        "unknown,violated; unknown: the tasks neither solved nor certified)")
    p.add_argument("--budget", type=float, default=1.0, metavar="K",
                   help="multiply the search's and the certificate's budgets by K >= 1 (oe.guided_budget and the "
                        "certificate's block updates; e.g. --resume --retry unknown --budget 4 gives the undecided "
                        "tasks four times more)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p = add(bsub, "report", "tables of a results file; with --out also CSV files and figures",
            "tooltransfer batch report out/small.sqlite --out out/small_report", _cmd_report)
    p.add_argument("db", type=Path, help="SQLite results file")
    p.add_argument("--out", type=Path, default=None, help="folder for results.csv, summary.csv, reasons.csv, figures")
    add(bsub, "schema", "print the JSON Schema of batch files", "tooltransfer batch schema > batch.schema.json",
        _cmd_schema)
    return group
