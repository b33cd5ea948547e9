"""Verdict benchmark: how many tasks the planner decides (solved, or infeasible with a certificate), and how fast.

Run with `python benchmarks/bench_verdicts.py` (or `make bench-verdicts`). Every task is planned with
:func:`tooltransfer.planner.planning.solve.solve` (the default variant, OE ``qp`` and SS ``opt``), which
gives it a verdict (:attr:`tooltransfer.planner.planning.plan.Plan.verdict`): ``solved``, ``infeasible``
with a certificate in ``plan.evidence`` (its ``kind``) or ``unknown``.

Tasks: the 60 of the execution benchmark (``problems/batch/execution_60.yaml``, seed 60, up to one
obstacle) and the 200 of ``problems/batch/verdicts_200.yaml`` (seed 2626, up to two obstacles); both
use the five library tools in turn. ``--count N`` takes the first N tasks of each file. Tasks run in
a process pool (``--workers``, default 2; :func:`bench_execution.run_jobs`); a task whose planning
raises or runs past ``--timeout`` is an ``error`` row, counted as undecided.

Report: the three counts with their shares and Wilson intervals (95 %), per task file and in all; the
certificates' kinds (and the unknown verdicts' evidence kinds and reasons, grouped, with the tasks whose
certificate was built but refused by its own check and those whose start or target no face holds on a window
as wide as the guided search's narrowest, ``hold_start`` and ``hold_target`` of the rows, and
``narrow_hold``); the verdicts by obstacle count; the planning time per verdict (median, p90, max of
``planning_time`` as ``solve --json`` prints it: the plan's ``time_total``, else the sum of its ``time_*``
metrics; ``time_certify`` apart); a per-tool table; the issue's targets (decided >= 97 %, median planning time
<= 2 s, p90 <= 10 s) each marked met or MISSED; the slowest tasks. ``--execute`` (off by default) also runs
every solved plan open loop on the simulated Omni
(:func:`tooltransfer.planner.execution.simulate.simulate_plan`) and closed loop on the nominal MuJoCo plant
(:func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`, the task's camera-noise seed, as
``bench_execution.py`` runs it) and reports the shares within 5 mm and 2 mm against the issue's 95 % (``make
bench-exec`` has the full execution figures: mismatched plants, the model's prediction).
``--json PATH`` writes every per-task row and the run's settings.

    python benchmarks/bench_verdicts.py --json out/verdicts.json   # 260 tasks
    python benchmarks/bench_verdicts.py --count 10                 # a quick look: 20 tasks
    python benchmarks/bench_verdicts.py --count 20 --execute

Single-threaded BLAS (``OPENBLAS_NUM_THREADS=1``); on the shared 2-core machine the times vary by
some percent from run to run. Adding a measure: a key of the row in :func:`run_verdict`, shown in
:func:`report`.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from bench_execution import (
    ROOT,
    Job,
    Row,
    _commit,
    _deadline,
    _exception,
    _is_exc,
    _met,
    _mm,
    _pct,
    _quantiles,
    _reason_group,
    _share,
    _task,
    make_jobs,
    run_jobs,
    write_json,
)

from tooltransfer.planner.apps.batch.execute import finite_or_none
from tooltransfer.planner.planning.verdicts.hold_windows import NARROW_HOLD, narrowly_held, widest_stored

BATCHES = (ROOT / "problems" / "batch" / "execution_60.yaml", ROOT / "problems" / "batch" / "verdicts_200.yaml")
VERDICTS = ("solved", "infeasible", "unknown")
TARGET_DECIDED, TARGET_MEDIAN, TARGET_P90 = 0.97, 2.0, 10.0
"""The issue's targets: the decided share, the median and p90 planning time per task [s]."""
WITHIN, WITHIN_CLOSED, TARGET_EXECUTED = 0.005, 0.002, 0.95
"""Open-loop and closed-loop final-error thresholds [m] of ``--execute``, and the issue's share of the solved
plans within each."""


@dataclass(frozen=True)
class VerdictJob(Job):
    """A :class:`bench_execution.Job` (planning only) and whether to execute a solved plan (open and closed
    loop)."""

    execute: bool = False


def _widest_holds(evidence: dict[str, Any]) -> dict[str, float | None]:
    """``hold_start``, ``hold_target``: the widest window [m] on which any face holds the puck there (an
    unknown's evidence ``holds``, :func:`~tooltransfer.planner.planning.verdicts.holds_at.face_holds`; -1 where
    no face does, None without that evidence)."""
    holds = evidence.get("holds") or {}
    return {f"hold_{where}": widest_stored(holds[where]) if where in holds else None for where in ("start", "target")}


def run_verdict(job: VerdictJob) -> Row:
    """Plan one task: its verdict, the evidence's kind, the times [s] (and, with ``job.execute``, the
    open-loop and closed-loop final errors [m] of a solved plan, the closed loop's status and reason); never
    raises for the task's own failures."""
    from tooltransfer.planner.planning.solve import solve

    row: Row = {"task_id": job.task_id, "kind": job.kind, "batch": Path(job.source).name, "index": job.index,
                "tool": job.tool, "variant": job.variant, "n_obstacles": job.n_obstacles, "status": None,
                "verdict": "error", "evidence_kind": None, "reason": "", "not_proved": None, "budget_limited": None,
                "hold_start": None, "hold_target": None, "narrow_hold": None,
                "planning_time": None, "time_certify": None, "plan_wall": None, "plan_cpu": None,
                "n_pushes": None, "open_loop_status": None, "open_loop_error": None, "closed_loop_status": None,
                "closed_loop_error": None, "closed_loop_reason": None, "worker": os.getpid()}
    started, cpu = time.perf_counter(), time.process_time()
    try:
        with _deadline(job.timeout, "planning"):
            plan = solve(_task(job), job.source)
    except Exception as exc:
        row.update(status=_exception(exc), plan_wall=time.perf_counter() - started, task_wall=row["plan_wall"])
        return row
    m, ev = plan.metrics, plan.evidence
    row.update(status=plan.status, verdict=plan.verdict, evidence_kind=ev.get("kind"), reason=(plan.reason or "")[:500],
               not_proved=(str(ev["not_proved"])[:300] if "not_proved" in ev else None),
               budget_limited=ev.get("budget_limited"), **_widest_holds(ev), narrow_hold=narrowly_held(ev),
               planning_time=plan.planning_time, time_certify=finite_or_none(m.get("time_certify")),
               plan_wall=time.perf_counter() - started, plan_cpu=time.process_time() - cpu,
               n_pushes=None if m.get("n_pushes") is None else round(m["n_pushes"]))
    if job.execute and plan.verdict == "solved":
        from tooltransfer.planner.execution.simulate import simulate_plan

        try:
            with _deadline(job.timeout, "open loop"):
                row.update(open_loop_status="ok", open_loop_error=simulate_plan(plan).final_error)
        except Exception as exc:
            row["open_loop_status"] = _exception(exc)
        from tooltransfer.planner.execution.closed_loop import execute_closed_loop

        try:
            with _deadline(job.timeout, "closed loop"):
                cl = execute_closed_loop(plan, seed=job.seed)
            row.update(closed_loop_status=cl.status, closed_loop_error=cl.final_error,
                       closed_loop_reason=(cl.reason or "")[:300])
        except Exception as exc:
            row["closed_loop_status"] = _exception(exc)
    row["task_wall"] = time.perf_counter() - started
    return row


def make_verdict_jobs(batches: Sequence[Path], count: int | None, timeout: float, execute: bool) -> list[VerdictJob]:
    """The generated tasks of every batch file in order (the first ``count`` of each), variant qp/opt."""
    out = []
    for batch in batches:
        for j in make_jobs(batch, count, [("qp", "opt")], False, False, 0, timeout, mismatch=False):
            out.append(VerdictJob(**{f.name: getattr(j, f.name) for f in fields(Job)}, execute=execute))
    return out


def rows_with_verdict(results: Path, verdict: str) -> tuple[list[Row], dict[str, VerdictJob]]:
    """The rows of a ``--json`` results file with ``verdict``, and the jobs of the run by task id (its batch files,
    else the files of that name in this checkout: a run made elsewhere). Raises ValueError with what is wrong (the
    file unreadable, or rows not in the run's batch files)."""
    import json

    try:
        data = json.loads(results.read_text())
        rows = [r for r in data["rows"] if r.get("verdict") == verdict]
        names, count = data["meta"]["batches"], data["meta"].get("count")
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise ValueError(f"{results}: not a bench_verdicts.py --json file that can be read: {exc}") from exc
    batches = [Path(b) if Path(b).is_file() else ROOT / "problems" / "batch" / Path(b).name for b in names]
    jobs = {j.task_id: j for j in make_verdict_jobs(batches, count, 600.0, False)}
    missing = [r["task_id"] for r in rows if r["task_id"] not in jobs]
    if missing:
        raise ValueError(f"{results}: rows not in the run's batch files: {missing}")
    return rows, jobs


def _verdict_of(r: Row) -> str:
    return r.get("verdict") or "error"


def _counts(rows: Sequence[Row]) -> str:
    """``solved k (share, [lo, hi])`` for each verdict, and the decided share."""
    from tooltransfer.planner.apps.batch.stats import wilson

    n = len(rows)
    c = Counter(_verdict_of(r) for r in rows)
    parts = []
    for v in (*VERDICTS, "error"):
        if v == "error" and not c[v]:
            continue
        lo, hi = wilson(c[v], n)
        parts.append(f"{v} {c[v]} ({_pct(c[v] / n)}, [{_pct(lo)}, {_pct(hi)}])")
    d = c["solved"] + c["infeasible"]
    lo, hi = wilson(d, n)
    return f"{n} tasks: " + ", ".join(parts) + f"; decided {d} ({100 * d / n:.1f} %, [{_pct(lo)}, {_pct(hi)}])"


def _sec(q: tuple[float, float, float] | None) -> tuple[str, str, str]:
    return ("-", "-", "-") if q is None else (f"{q[0]:.2f}", f"{q[1]:.2f}", f"{q[2]:.2f}")


def report(rows: Sequence[Row], wall: float, con: Any) -> dict[str, Any]:
    """Print the tables of the rows (module docstring); returns the headline figures."""
    from rich import box
    from rich.table import Table

    if not rows:
        con.print("no tasks")
        return {}
    con.rule("verdicts (Wilson 95 % intervals)")
    for batch in dict.fromkeys(r["batch"] for r in rows):
        con.print(f"{batch}: " + _counts([r for r in rows if r["batch"] == batch]))
    con.print("all: " + _counts(rows))
    kinds = Counter(r["evidence_kind"] for r in rows if _verdict_of(r) == "infeasible")
    con.print("certificates' kinds: " + (", ".join(f"{k} {n}" for k, n in kinds.most_common()) or "-"))
    unknown = [r for r in rows if _verdict_of(r) == "unknown"]
    if unknown:
        con.print("unknown evidence kinds: " + ", ".join(
            f"{k} {n}" for k, n in Counter(r["evidence_kind"] for r in unknown).most_common()))
        for why, n in Counter(_reason_group(r.get("not_proved") or "")[:160] for r in unknown).most_common(5):
            con.print(f"  not proved x{n}: {why}")
        spent = [r["task_id"] for r in unknown if r.get("budget_limited")]
        con.print(f"  stopped on the search's or the certificate's budget: {len(spent)}"
                  + (f" ({', '.join(spent)}; --budget K may decide them)" if spent else ""))
        narrow = [r["task_id"] for r in unknown if r.get("narrow_hold")]
        con.print(f"  the start or the target held only on windows under {NARROW_HOLD * 1e3:g} mm (evidence 'holds'): "
                  f"{len(narrow)}" + (f" ({', '.join(narrow)})" if narrow else ""))
        failed = [r["task_id"] for r in unknown if "check failed" in (r.get("not_proved") or "")]
        if failed:
            con.print("  certificates built but refused by their own check: " + ", ".join(failed))
    by_obstacles = Counter((r["n_obstacles"], _verdict_of(r)) for r in rows)
    con.print("by obstacles: " + "; ".join(
        f"{k}: " + ", ".join(f"{v} {by_obstacles[k, v]}" for v in (*VERDICTS, "error") if by_obstacles[k, v])
        for k in sorted({r["n_obstacles"] for r in rows})))
    for r in rows:
        if _verdict_of(r) == "error":
            con.print(f"  {r['task_id']}: {r['status']}")

    con.print("planning time per task: planning_time of solve --json; certify: time_certify, a part of it")
    t = Table("verdict", "tasks", "median s", "p90 s", "max s", "certify median s", "certify max s",
              box=box.SIMPLE_HEAD)
    for v in (*VERDICTS, "all"):
        vr = rows if v == "all" else [r for r in rows if _verdict_of(r) == v]
        q = _quantiles([r["planning_time"] for r in vr if r.get("planning_time") is not None])
        qc = _quantiles([r["time_certify"] for r in vr if r.get("time_certify") is not None])
        t.add_row(v, str(len(vr)), *_sec(q), *(_sec(qc)[0::2]))
    con.print(t)

    t = Table("tool", "tasks", "solved", "infeasible", "unknown", "error", "decided", "median s", "p90 s", "max s",
              box=box.SIMPLE_HEAD)
    con.print("per tool:")
    for tool in dict.fromkeys(r["tool"] for r in rows):
        tr = [r for r in rows if r["tool"] == tool]
        c = Counter(_verdict_of(r) for r in tr)
        q = _quantiles([r["planning_time"] for r in tr if r.get("planning_time") is not None])
        t.add_row(tool, str(len(tr)), *(str(c[v]) for v in (*VERDICTS, "error")),
                  _pct((c["solved"] + c["infeasible"]) / len(tr)), *_sec(q))
    con.print(t)

    ran = [r for r in rows if r.get("open_loop_status") is not None]
    closed = [r for r in ran if r.get("closed_loop_status") is not None]
    executed = [_executed(con, runs, loop, within, plant) for runs, loop, within, plant in
                ((ran, "open", WITHIN, "simulated Omni"), (closed, "closed", WITHIN_CLOSED, "nominal MuJoCo plant"))
                if runs]  # the execution targets' lines
    for r in closed:
        e = r["closed_loop_error"]
        if e is None or e > WITHIN_CLOSED:
            con.print(f"  {r['task_id']} ({r['tool']}, {r['n_obstacles']} obstacles, {r['n_pushes']} pushes): "
                      f"{r['closed_loop_status']} {_mm(e)} mm {(r.get('closed_loop_reason') or '')[:110]}")

    n = len(rows)
    decided = sum(_verdict_of(r) in ("solved", "infeasible") for r in rows) / n
    times = [r["planning_time"] for r in rows if r.get("planning_time") is not None]
    q = _quantiles(times) or (float("nan"),) * 3
    con.print("targets:")
    con.print(f"  decided (solved + certified infeasible) >= {100 * TARGET_DECIDED:.0f} %: {100 * decided:.1f} % "
              f"{_met(decided >= TARGET_DECIDED)}")
    con.print(f"  median planning time <= {TARGET_MEDIAN:g} s: {q[0]:.2f} s {_met(q[0] <= TARGET_MEDIAN)}")
    con.print(f"  p90 planning time <= {TARGET_P90:g} s: {q[1]:.2f} s {_met(q[1] <= TARGET_P90)}")
    for line in executed:
        con.print(line)
    if len(times) < n:
        con.print(f"  ({n - len(times)} tasks without a planning time: errors, left out of the times)")

    slow = sorted((r for r in rows if r.get("planning_time") is not None), key=lambda r: -r["planning_time"])[:5]
    con.print("slowest: " + ", ".join(f"{r['task_id']} {_verdict_of(r)} {r['planning_time']:.1f} s" for r in slow))
    busy = sum(r.get("task_wall") or 0.0 for r in rows)
    con.print(f"total: {n} tasks in {wall:.1f} s wall ({wall / 60:.1f} min); sum of task times {busy:.1f} s")
    return {"decided": decided, "median": q[0], "p90": q[1], "max": q[2]}


def _executed(con: Any, runs: Sequence[Row], loop: str, within: float, plant: str) -> str:
    """Print the ``loop`` ("open" or "closed") execution of the solved plans ``runs`` on ``plant``: the share
    within ``within`` [m] (an exception a miss), the median and max error, how the runs ended; return the
    issue's target line for it."""
    errs = [r[f"{loop}_loop_error"] for r in runs if not _is_exc(r[f"{loop}_loop_status"])]
    share = _share(errs, len(runs), within) or 0.0
    q = _quantiles([e for e in errs if e is not None])
    ends = Counter(r[f"{loop}_loop_status"] for r in runs)
    con.print(f"{loop} loop ({plant}) of the {len(runs)} solved plans: within {1e3 * within:.0f} mm "
              f"{100 * share:.1f} % (an exception a miss: {len(runs) - len(errs)}); median {_mm(q and q[0])} mm, "
              f"max {_mm(q and q[2])} mm; ends: " + ", ".join(f"{k} {n}" for k, n in ends.most_common()))
    return (f"  solved plans {loop} loop >= {100 * TARGET_EXECUTED:.0f} % within {1e3 * within:.0f} mm: "
            f"{100 * share:.1f} % {_met(share >= TARGET_EXECUTED)}")


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--batch", type=Path, action="append", default=None,
                    help="batch file of generated tasks (repeat for several; default the two of the docstring)")
    ap.add_argument("--count", type=int, default=None, help="only the first N tasks of each batch file")
    ap.add_argument("--workers", type=int, default=2, help="worker processes (1: in this process)")
    ap.add_argument("--execute", action="store_true",
                    help="also run solved plans open and closed loop on the simulated Omni (off by default)")
    ap.add_argument("--timeout", type=float, default=600.0,
                    help="per task and stage (planning, open loop, closed loop) [s], an error row past it; 0: none")
    ap.add_argument("--json", type=Path, default=None, help="write every per-task row to this file")
    ap.add_argument("--quiet", action="store_true", help="no line per finished task")
    args = ap.parse_args(argv)

    from rich.console import Console

    con = Console(width=None if sys.stdout.isatty() else 150, markup=False, highlight=False)
    batches = args.batch or list(BATCHES)
    jobs = make_verdict_jobs(batches, args.count, args.timeout, args.execute)
    commit = _commit()
    con.print(f"verdict benchmark: {len(jobs)} tasks ({', '.join(b.name for b in batches)}"
              f"{'' if args.count is None else f', first {args.count} of each'}; variant qp/opt; open and closed loop "
              f"{'on' if args.execute else 'off'}); {args.workers} workers; commit {commit}")
    t0 = time.perf_counter()
    done = 0

    def on_row(r: Row) -> None:
        nonlocal done
        done += 1
        if not args.quiet:
            pt = "-" if r.get("planning_time") is None else f"{r['planning_time']:.2f} s"
            extra = r.get("evidence_kind") or r.get("status") or ""
            if r.get("open_loop_error") is not None:
                extra += f" | open {_mm(r['open_loop_error'])} mm"
            if r.get("closed_loop_status") is not None:
                extra += f" | closed {r['closed_loop_status']} {_mm(r.get('closed_loop_error'))} mm"
            print(f"[{done:>3}/{len(jobs)}] {r['task_id']:<14} {r['tool']:<9} {_verdict_of(r):<10} {pt:>8} "
                  f"{extra}", flush=True)

    rows = run_jobs(jobs, args.workers, on_row, run=run_verdict)
    wall = time.perf_counter() - t0
    for r in rows:  # crash rows of run_jobs lack the verdict's keys
        r.setdefault("verdict", "error")
        r.setdefault("batch", next((b.name for b in batches if r["task_id"].startswith(_name(b))), "?"))
    headline = report(rows, wall, con)
    if args.json is not None:
        meta = {"commit": commit, "batches": [str(b) for b in batches], "count": args.count, "variant": "qp/opt",
                "execute": args.execute, "workers": args.workers, "timeout": args.timeout, "wall": wall,
                "headline": headline, "python": sys.version.split()[0], "argv": sys.argv[1:],
                "finished": time.strftime("%Y-%m-%d %H:%M:%S")}
        write_json(args.json, rows, meta)
        con.print(f"rows written to {args.json}")


def _name(batch: Path) -> str:
    import yaml

    return str(yaml.safe_load(batch.read_text())["name"]) + "-"


if __name__ == "__main__":
    main()
