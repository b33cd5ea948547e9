"""Statistics of a batch's results: per tool and variant, success rate with a Wilson interval,
violated (a whole plan that breaks a hard check: :func:`tooltransfer.planner.planning.solve.hard_check_failures`;
counted apart, never as a success), infeasible, error and timeout counts with the top reasons,
planning-time percentiles, violation maxima and, for a batch run with ``--simulate``, executed
success; rich tables (the top reasons grouped, numbers shown as ``#``), CSV files (quantities named
with their units; ``reasons.csv`` every reason in full) and ``report.html``.

Executed success: a solved plan executed on the simulated platform succeeds within 2 mm (5 mm)
when the object ends within 2 mm (5 mm) of the target (:data:`EXEC_TOLS`), open loop and closed
loop; given as a share of the executed solved plans (every solved plan is executed; an execution
that raised or timed out counts as a miss) and of all tasks (planned and executed: the end-to-end
rate), beside the closed loop's statuses and the median final errors.

A solved row is also checked: ``valid`` counts solved plans whose measured cone violation is at
most :data:`CONE_TOL` [rad], reach violation at most :data:`REACH_TOL` [m], penetration (the
object into an obstacle, or the tool into the object or an obstacle during a switch) at most
:data:`PENETRATION_TOL` [m], and without joint-limit violation. (The paper's mapping variant does
not enforce the cone, so its solved plans can break it; the table shows by how much.)
"""

from __future__ import annotations

import csv
import io
import json
import re
from collections import Counter, defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from tooltransfer.atomic import write_bytes
from tooltransfer.planner.apps.batch.stats import EXEC_TOLS, wilson
from tooltransfer.planner.common.metric_units import display, label
from tooltransfer.planner.planning.verdicts.hold_windows import NARROW_HOLD, narrowly_held

CONE_TOL = 0.01
REACH_TOL = 1e-3
PENETRATION_TOL = 1e-6


def is_valid(r: dict[str, Any]) -> bool:
    """A solved row whose measured violations are within the tolerances (module docstring)."""
    def num(k: str) -> float:
        v = r.get(k)
        return 0.0 if v is None else float(v)

    return (r.get("status") == "solved" and num("cone_violation_max") <= CONE_TOL
            and num("reach_violation_max") <= REACH_TOL and num("penetration_max") <= PENETRATION_TOL
            and num("joint_limit_violation_max") <= 1e-9)


@dataclass(frozen=True)
class GroupStats:
    """Statistics of one tool (or ``all``) and variant. Times [s], lengths [m], angles [rad]."""

    tool: str
    variant: str
    n: int
    solved: int
    infeasible: int
    error: int
    timeout: int
    rate: float
    ci_low: float
    ci_high: float
    valid: int
    time_p50: float
    time_p90: float
    time_p99: float
    time_max: float
    cone_violation_max: float
    reach_violation_max: float
    penetration_max: float
    joint_limit_violation_max: float
    obstacle_clearance_min: float
    goal_error_max: float
    sim_n: int
    sim_success: int
    sim_rate: float
    sim_ci_low: float
    sim_ci_high: float
    sim_final_error_median: float
    ol_n: int = 0
    ol_2mm: int = 0
    ol_5mm: int = 0
    ol_2mm_of_solved: float = float("nan")
    ol_5mm_of_solved: float = float("nan")
    ol_2mm_of_all: float = float("nan")
    ol_5mm_of_all: float = float("nan")
    ol_error_median: float = float("nan")
    ol_error_p90: float = float("nan")
    ol_failed: int = 0
    ol_wall_median: float = float("nan")
    cl_n: int = 0
    cl_2mm: int = 0
    cl_5mm: int = 0
    cl_2mm_of_solved: float = float("nan")
    cl_5mm_of_solved: float = float("nan")
    cl_2mm_of_all: float = float("nan")
    cl_5mm_of_all: float = float("nan")
    cl_2mm_all_ci_low: float = float("nan")
    cl_2mm_all_ci_high: float = float("nan")
    cl_error_median: float = float("nan")
    cl_error_p90: float = float("nan")
    cl_statuses: str = ""
    cl_replans_median: float = float("nan")
    cl_replan_time_max: float = float("nan")
    cl_wall_median: float = float("nan")
    violated: int = 0
    unknown: int = 0
    infeasible_ci_low: float = float("nan")
    infeasible_ci_high: float = float("nan")
    unknown_ci_low: float = float("nan")
    unknown_ci_high: float = float("nan")
    certificates: str = ""
    unknown_on_budget: int = 0
    unknown_narrow: int = 0


def _pct(a: np.ndarray, q: float) -> float:
    return float(np.percentile(a, q)) if a.size else float("nan")


def _share(k: int, n: int) -> float:
    return k / n if n else float("nan")


def execution_stats(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The executed-success fields of :class:`GroupStats` for one group's ``rows`` (module docstring)."""
    n = len(rows)
    ok = [r for r in rows if r["status"] == "solved"]
    out: dict[str, Any] = {}
    for tag, key in (("ol", "open_loop"), ("cl", "closed_loop")):
        ran = [r for r in ok if r.get(f"{key}_status") is not None]
        err = _vals(ran, f"{key}_error")
        k2, k5 = (int(np.sum(err <= tol)) for tol in EXEC_TOLS)
        out.update({f"{tag}_n": len(ran), f"{tag}_2mm": k2, f"{tag}_5mm": k5,
                    f"{tag}_2mm_of_solved": _share(k2, len(ran)), f"{tag}_5mm_of_solved": _share(k5, len(ran)),
                    f"{tag}_2mm_of_all": _share(k2, n) if ran else float("nan"),
                    f"{tag}_5mm_of_all": _share(k5, n) if ran else float("nan"),
                    f"{tag}_error_median": _agg(err, "median"), f"{tag}_error_p90": _pct(err, 90),
                    f"{tag}_wall_median": _agg(_vals(ran, f"{key}_wall_time"), "median")})
        if tag == "ol":
            out["ol_failed"] = sum(r.get("open_loop_status") != "done" for r in ran)
        else:
            lo, hi = wilson(k2, n) if ran else (float("nan"), float("nan"))
            st = Counter(r["closed_loop_status"] for r in ran)
            out.update(cl_2mm_all_ci_low=lo, cl_2mm_all_ci_high=hi,
                       cl_statuses=", ".join(f"{k} {v}" for k, v in st.most_common()),
                       cl_replans_median=_agg(_vals(ran, "closed_loop_replans"), "median"),
                       cl_replan_time_max=_agg(_vals(ran, "closed_loop_replan_time_max"), "max"))
    return out


def _vals(rows: Iterable[dict[str, Any]], key: str) -> np.ndarray:
    return np.array([float(r[key]) for r in rows if r.get(key) is not None], dtype=np.float64)


def _agg(a: np.ndarray, how: str) -> float:
    if a.size == 0:
        return float("nan")
    return float(a.max() if how == "max" else a.min() if how == "min" else np.median(a))


def group_stats(tool: str, variant: str, rows: Sequence[dict[str, Any]]) -> GroupStats:
    """Statistics of ``rows`` (one group)."""
    c = Counter(r["status"] for r in rows)
    n = len(rows)
    lo, hi = wilson(c["solved"], n)
    timed = _vals([r for r in rows if r["status"] in ("solved", "violated", "infeasible", "unknown")], "time_total")
    pct = np.percentile(timed, [50, 90, 99]) if timed.size else [float("nan")] * 3
    ok = [r for r in rows if r["status"] == "solved"]
    sim = [r for r in ok if r.get("sim_success") is not None]
    k = sum(int(r["sim_success"]) for r in sim)
    slo, shi = wilson(k, len(sim))
    return GroupStats(
        tool, variant, n, c["solved"], c["infeasible"], c["error"], c["timeout"], c["solved"] / n if n else 0.0,
        lo, hi, sum(is_valid(r) for r in ok), *map(float, pct), _agg(timed, "max"),
        _agg(_vals(ok, "cone_violation_max"), "max"), _agg(_vals(ok, "reach_violation_max"), "max"),
        _agg(_vals(ok, "penetration_max"), "max"), _agg(_vals(ok, "joint_limit_violation_max"), "max"),
        _agg(_vals(ok, "obstacle_clearance_min"), "min"), _agg(_vals(ok, "goal_error"), "max"),
        len(sim), k, k / len(sim) if sim else float("nan"), slo, shi,
        _agg(_vals(sim, "sim_final_error"), "median"), **execution_stats(rows), violated=c["violated"],
        unknown=c["unknown"] + c["violated"], **_verdict_cis(c, n), certificates=_certificate_kinds(rows),
        unknown_on_budget=sum(_evidence(r).get("budget_limited") is True for r in rows if r["status"] == "unknown"),
        unknown_narrow=sum(narrowly_held(_evidence(r)) for r in rows if r["status"] == "unknown"),
    )


def _verdict_cis(c: Counter, n: int) -> dict[str, float]:
    """Wilson intervals of the certified-infeasible and the unknown (violated included) rates."""
    ilo, ihi = wilson(c["infeasible"], n)
    ulo, uhi = wilson(c["unknown"] + c["violated"], n)
    return {"infeasible_ci_low": ilo, "infeasible_ci_high": ihi, "unknown_ci_low": ulo, "unknown_ci_high": uhi}


def _evidence(row: dict[str, Any]) -> dict[str, Any]:
    """A stored row's verdict evidence (empty where it has none or its JSON is unreadable)."""
    try:
        evidence = json.loads(row.get("metrics_json") or "{}").get("evidence", {})
    except (ValueError, AttributeError):
        return {}
    return evidence if isinstance(evidence, dict) else {}


def _certificate_kinds(rows: Sequence[dict[str, Any]]) -> str:
    """The certificates' kinds of the infeasible rows, counted (``"backward_reachable 3, ..."``)."""
    kinds: Counter = Counter(_evidence(r).get("kind", "?") for r in rows if r["status"] == "infeasible")
    return ", ".join(f"{k} {v}" for k, v in kinds.most_common())


def summarize(rows: Sequence[dict[str, Any]]) -> list[GroupStats]:
    """Per tool and variant, then per variant over all tools (tool ``all``)."""
    groups: dict[tuple[str, str], list] = defaultdict(list)
    for r in rows:
        groups[(r.get("tool") or "?", r["variant"])].append(r)
        groups[("all", r["variant"])].append(r)
    order = sorted(groups, key=lambda k: (k[0] == "all", k[0], k[1]))
    return [group_stats(t, v, groups[(t, v)]) for t, v in order]


_NUM = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?|\[[^\]]*\]")


def reason_class(reason: str) -> str:
    """A reason with its numbers (and bracketed values) replaced by ``#``, cut to 110 characters."""
    text = _NUM.sub("#", reason or "(no reason)").strip()
    return text if len(text) <= 110 else text[:107] + "..."


def top_reasons(rows: Sequence[dict[str, Any]], k: int = 3) -> list[dict[str, Any]]:
    """The ``k`` most frequent reason classes per variant and failing status (of planning, and of
    the executions of solved plans: ``open loop error``, ``closed loop closest``, ...)."""
    groups: dict[tuple[str, str], Counter] = defaultdict(Counter)
    for r in rows:
        for status, reason in failure_reasons(r):
            groups[(r["variant"], status)][reason_class(reason)] += 1
    return [{"variant": v, "status": s, "count": n, "reason": text}
            for (v, s), cnt in sorted(groups.items()) for text, n in cnt.most_common(k)]


def failure_reasons(r: dict[str, Any]) -> list[tuple[str, str]]:
    """The ``(status, reason)`` pairs of row ``r`` that are not successes: its planning status and
    reason when not solved, else each execution that did not end done or reached (``closed loop
    closest``, ...); reasons in full."""
    if r["status"] != "solved":
        return [(r["status"], r.get("reason") or "")]
    out = []
    for key, loop in (("open_loop", "open loop"), ("closed_loop", "closed loop")):
        st = r.get(f"{key}_status")
        if st not in (None, "done", "reached"):
            out.append((f"{loop} {st}", r.get(f"{key}_reason") or ""))
    return out


def all_reasons(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Every distinct reason in full per variant and failing status (:func:`failure_reasons`) with
    how many rows gave it, most frequent first: ``reasons.csv``."""
    groups: dict[tuple[str, str], Counter] = defaultdict(Counter)
    for r in rows:
        for status, reason in failure_reasons(r):
            groups[(r["variant"], status)][reason] += 1
    return [{"variant": v, "status": s, "count": n, "reason": text}
            for (v, s), cnt in sorted(groups.items()) for text, n in cnt.most_common()]


def _fmt(v: float, scale: float = 1.0, digits: int = 2) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v * scale:.{digits}f}"


#: The violations table's columns: header, the :class:`GroupStats` field, the result column whose unit
#: (:func:`tooltransfer.planner.common.metric_units.display`) the field is shown in, digits.
VIOLATION_COLUMNS = (
    ("cone", "cone_violation_max", "cone_violation_max", 3),
    ("reach", "reach_violation_max", "reach_violation_max", 2),
    ("penetr.", "penetration_max", "penetration_max", 2),
    ("joints", "joint_limit_violation_max", "joint_limit_violation_max", 3),
    ("clear. min", "obstacle_clearance_min", "obstacle_clearance_min", 2),
    ("goal err", "goal_error_max", "goal_error", 2),
)


def print_report(stats: Sequence[GroupStats], reasons: Sequence[dict[str, Any]], console: Console) -> None:
    """The tables: outcomes and times, violations, executed success (when plans were executed), top
    reasons. Units from :mod:`tooltransfer.planner.common.metric_units` (planning times in ms)."""
    t = Table(title="outcomes per tool and variant (success: solved; 95% Wilson intervals; infeasible: certified; "
                    "unknown: neither solved nor certified, violated plans included)")
    _, ms = display("time_total", "ms")
    for col in ("tool", "variant", "n", "solved", "rate [%]", "95% CI [%]", "valid", "violated", "infeas.",
                "infeas. CI [%]", "unknown", "unknown CI [%]", "error", "timeout",
                *(label(p, "time_total", "ms") for p in ("t50", "t90", "t99"))):
        t.add_column(escape(col), justify="left" if col in ("tool", "variant") else "right")
    for s in stats:
        t.add_row(s.tool, s.variant, str(s.n), str(s.solved), _fmt(s.rate, 100, 1),
                  f"{_fmt(s.ci_low, 100, 1)}-{_fmt(s.ci_high, 100, 1)}", str(s.valid), str(s.violated),
                  str(s.infeasible), f"{_fmt(s.infeasible_ci_low, 100, 1)}-{_fmt(s.infeasible_ci_high, 100, 1)}",
                  str(s.unknown), f"{_fmt(s.unknown_ci_low, 100, 1)}-{_fmt(s.unknown_ci_high, 100, 1)}",
                  str(s.error), str(s.timeout), _fmt(s.time_p50, ms, 0), _fmt(s.time_p90, ms, 0),
                  _fmt(s.time_p99, ms, 0), end_section=s.tool == "all" and s is stats[-1])
    console.print(t)
    for s in stats:
        if s.certificates:
            console.print(f"certificates of {escape(s.tool)} {escape(s.variant)}: {escape(s.certificates)}")
    for s in stats:
        plain = s.unknown - s.violated  # violated rows are counted with the unknown ones
        if plain > 0:
            console.print(f"unknown of {escape(s.tool)} {escape(s.variant)}: {plain}, {s.unknown_on_budget} of them "
                          "stopped on the search's or the certificate's budget (`batch run --resume --retry unknown "
                          "--budget K` may decide those; the others ended within their budgets, where a larger one is "
                          "unlikely to help)" + (f"; {s.unknown_narrow} held at the start or the target only on "
                                                 f"contact windows under {NARROW_HOLD * 1e3:g} mm (evidence 'holds')"
                                                 if s.unknown_narrow else ""))
    v = Table(title="solved plans: violation maxima, clearance")
    for col in ("tool", "variant", *(label(head, column) for head, _, column, _ in VIOLATION_COLUMNS)):
        v.add_column(escape(col), justify="left" if col in ("tool", "variant") else "right")
    for s in stats:
        v.add_row(s.tool, s.variant, *(_fmt(getattr(s, name), display(column)[1], digits)
                                       for _, name, column, digits in VIOLATION_COLUMNS))
    console.print(v)
    if any(s.ol_n or s.cl_n for s in stats):
        print_execution(stats, console)
    if reasons:
        r = Table(title="top reasons (numbers shown as #)")
        for col in ("variant", "status", "count", "reason"):
            r.add_column(col, justify="right" if col == "count" else "left")
        for e in reasons:
            r.add_row(e["variant"], e["status"], str(e["count"]), escape(e["reason"]))
        console.print(r)


def _cell(s: GroupStats, which: str) -> str:
    """``which`` (e.g. ``cl_2mm``) as ``count: % of executed solved plans / % of all tasks``."""
    if not getattr(s, f"{which[:2]}_n"):
        return "-"
    k, solved, every = (getattr(s, f"{which}{x}") for x in ("", "_of_solved", "_of_all"))
    return f"{k}: {_fmt(solved, 100, 0)} / {_fmt(every, 100, 0)}"


def tolerance_text(tol: float) -> str:
    """An executed-success tolerance ``tol`` [m] in the unit the final errors are shown in: ``"2 mm"``."""
    u, f = display("open_loop_error")
    return f"{tol * f:g} {u}"


def print_execution(stats: Sequence[GroupStats], console: Console) -> None:
    """The executed-success table (module docstring)."""
    tols = [tolerance_text(tol) for tol in EXEC_TOLS]
    e = Table(title="executed success on the simulated platform: open loop (OL) and closed loop (CL)",
              caption=f"OL/CL <={tols[0]} ({tols[1]}): the object ends within {tols[0]} ({tols[1]}) of the target; "
              "cells: count: % of the executed solved plans / % of all tasks; CI: Wilson, of all tasks; err: median "
              "final error; t: median wall time of one execution")
    _, m_ol = display("open_loop_error")
    _, m_cl = display("closed_loop_error")
    _, s_wall = display("open_loop_wall_time")
    for col in ("tool", "variant", "solved", "exec.", *(f"{loop} <={tol}" for loop in ("OL", "CL") for tol in tols),
                f"CL <={tols[0]} 95% CI [%]", label("OL err", "open_loop_error"), label("CL err", "closed_loop_error"),
                "CL statuses", "CL replans (med)", label("t OL/CL", "open_loop_wall_time")):
        e.add_column(escape(col), justify="left" if col in ("tool", "variant", "CL statuses") else "right")
    for s in stats:
        e.add_row(s.tool, s.variant, str(s.solved), str(max(s.ol_n, s.cl_n)),
                  *(_cell(s, w) for w in ("ol_2mm", "ol_5mm", "cl_2mm", "cl_5mm")),
                  f"{_fmt(s.cl_2mm_all_ci_low, 100, 1)}-{_fmt(s.cl_2mm_all_ci_high, 100, 1)}" if s.cl_n else "-",
                  _fmt(s.ol_error_median, m_ol), _fmt(s.cl_error_median, m_cl), s.cl_statuses or "-",
                  _fmt(s.cl_replans_median, 1, 0),
                  f"{_fmt(s.ol_wall_median, s_wall, 1)}/{_fmt(s.cl_wall_median, s_wall, 1)}")
    console.print(e)


def chosen_tools(rows: Sequence[dict[str, Any]]) -> dict[str, int]:
    """How often each tool was chosen, most often first, over the rows of a ``tools: choose`` batch (those
    whose ``metrics_json`` holds a ``"choice"``; ``none``: no tool solved the task); empty for other batches."""
    counts: Counter = Counter()
    for r in rows:
        text = r.get("metrics_json") or ""
        if '"choice"' in text and r["status"] not in ("error", "timeout"):
            counts[r.get("tool") or "?"] += 1
    return dict(counts.most_common())


def write_csv(path: Path, rows: Sequence[dict[str, Any]], columns: Sequence[str] | None = None) -> Path:
    """Write ``rows`` as CSV (``columns`` default: the first row's keys)."""
    cols = list(columns) if columns is not None else (list(rows[0]) if rows else [])
    buf = io.StringIO(newline="")
    w = csv.DictWriter(buf, fieldnames=cols, extrasaction="ignore")
    w.writeheader()
    w.writerows(rows)
    return write_bytes(path, buf.getvalue().encode())  # atomically: never half a table (CRLF rows as csv writes)


def write_report(db: str | Path, out: str | Path | None, console: Console | None = None) -> list[Path]:
    """Print the report of the store ``db``; with ``out``, write ``results.csv``, ``summary.csv``,
    ``reasons.csv`` (column names with their units: :mod:`tooltransfer.planner.apps.batch.units`;
    reasons in full), the figures and ``report.html`` (:mod:`tooltransfer.planner.apps.batch.html_report`)
    there. Returns the written paths.

    The store is opened read-only and never changed (a read-only file or folder is fine); messages
    name the file as the command's ``db`` argument. An empty file, or a store without rows, has
    nothing to report (said so, no error); a file that is not a store, or one holding values of the
    wrong kind, raises :class:`~tooltransfer.errors.InputError` naming it."""
    from tooltransfer.errors import InputError
    from tooltransfer.planner.apps.batch.store import ResultStore

    p = Path(db)
    if not p.is_file():
        raise InputError(f"db {p}", "an existing results file (written by tooltransfer batch run)",
                         "no such file" if not p.exists() else "not a regular file")
    if console is None:
        console = Console()
        if not console.is_terminal:
            console.width = 180  # files and pipes: whole tables
    if p.stat().st_size == 0:
        console.print(f"{escape(str(p))}: an empty file, no results to report")
        return []
    with ResultStore(p, readonly=True, field="db") as store:  # the file is never changed
        if store.note:
            console.print(f"note: {escape(store.note)}")
        store.check_rows()  # numbers where numbers belong
        rows = store.rows()
        meta = store.meta()
        tasks = store.task_documents()
    if not rows:
        console.print(f"{escape(str(p))}: no results yet" + (" (an SQLite file without tables)" if store.empty else ""))
        return []
    stats = summarize(rows)
    reasons = top_reasons(rows)
    console.print(f"batch {escape(str(meta.get('batch_name', '?')))}: {len(rows)} results in {escape(str(p))}")
    print_report(stats, reasons, console)
    chosen = chosen_tools(rows)
    if chosen:
        console.print("tools chosen (tools: choose): " + ", ".join(f"{escape(t)} {n}" for t, n in chosen.items()))
    if out is None:
        return []
    from tooltransfer.planner.apps.batch.units import SUMMARY_UNITS, columns_with_units, rows_with_units

    folder = Path(out)
    results = [{**r, "valid": int(is_valid(r))} for r in rows]
    names = [f.name for f in fields(GroupStats)]
    written = [write_csv(folder / "results.csv", rows_with_units(results), columns_with_units(list(results[0]))),
               write_csv(folder / "summary.csv", rows_with_units([asdict(s) for s in stats], SUMMARY_UNITS),
                         columns_with_units(names, SUMMARY_UNITS)),
               write_csv(folder / "reasons.csv", all_reasons(rows), ["variant", "status", "count", "reason"])]
    from tooltransfer.planner.apps.batch.figures import plot_batch
    from tooltransfer.planner.apps.batch.html_report import write_html_report

    written += plot_batch(rows, folder)
    try:
        written.append(write_html_report(rows, stats, all_reasons(rows), meta, tasks, folder / "report.html"))
    except ImportError as exc:  # Bokeh missing: the tables, CSV files and figures are there all the same
        console.print(f"note: no report.html: {escape(str(exc))}")  # how to install it
    return written
