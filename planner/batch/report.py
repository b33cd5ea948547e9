"""Statistics of a batch's results: per tool and variant, success rate with a Wilson interval,
infeasible, error and timeout counts with the top reasons, planning-time percentiles, violation
maxima and simulated success; rich tables and CSV files.

A solved row is also checked: ``valid`` counts solved plans whose measured cone violation is at
most :data:`CONE_TOL` [rad], reach violation at most :data:`REACH_TOL` [m], penetration (the
object into an obstacle, or the tool into the object or an obstacle during a switch) at most
:data:`PENETRATION_TOL` [m], and without joint-limit violation. (The paper's mapping variant does
not enforce the cone, so its solved plans can break it; the table shows by how much.)
"""

from __future__ import annotations

import csv
import re
from collections import Counter, defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table
from scipy.stats import binomtest

CONE_TOL = 0.01
REACH_TOL = 1e-3
PENETRATION_TOL = 1e-6
CONFIDENCE = 0.95


def wilson(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson score interval of a success rate ``k / n`` (``(nan, nan)`` for n = 0)."""
    if n == 0:
        return (float("nan"), float("nan"))
    ci = binomtest(k, n).proportion_ci(confidence_level=confidence, method="wilson")
    return (float(ci.low), float(ci.high))


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
    timed = _vals([r for r in rows if r["status"] in ("solved", "infeasible")], "time_total")
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
        _agg(_vals(sim, "sim_final_error"), "median"),
    )


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
    """The ``k`` most frequent reason classes per variant and failing status."""
    groups: dict[tuple[str, str], Counter] = defaultdict(Counter)
    for r in rows:
        if r["status"] != "solved":
            groups[(r["variant"], r["status"])][reason_class(r.get("reason") or "")] += 1
    return [{"variant": v, "status": s, "count": n, "reason": text}
            for (v, s), cnt in sorted(groups.items()) for text, n in cnt.most_common(k)]


def _fmt(v: float, scale: float = 1.0, digits: int = 2) -> str:
    return "-" if v is None or not np.isfinite(v) else f"{v * scale:.{digits}f}"


def print_report(stats: Sequence[GroupStats], reasons: Sequence[dict[str, Any]], console: Console) -> None:
    """The tables: outcomes and times, violations and simulation, top reasons."""
    t = Table(title="outcomes per tool and variant (success: solved; 95% Wilson interval)")
    for col in ("tool", "variant", "n", "solved", "rate [%]", "95% CI [%]", "valid", "infeas.", "error",
                "timeout", "t50 [ms]", "t90 [ms]", "t99 [ms]"):
        t.add_column(col, justify="left" if col in ("tool", "variant") else "right")
    for s in stats:
        t.add_row(s.tool, s.variant, str(s.n), str(s.solved), _fmt(s.rate, 100, 1),
                  f"{_fmt(s.ci_low, 100, 1)}-{_fmt(s.ci_high, 100, 1)}", str(s.valid), str(s.infeasible),
                  str(s.error), str(s.timeout), _fmt(s.time_p50, 1e3, 0), _fmt(s.time_p90, 1e3, 0),
                  _fmt(s.time_p99, 1e3, 0), end_section=s.tool == "all" and s is stats[-1])
    console.print(t)
    v = Table(title="solved plans: violation maxima, clearance, simulated success")
    for col in ("tool", "variant", "cone [rad]", "reach [mm]", "penetr. [mm]", "joints [rad]", "clear. min [mm]",
                "goal err [mm]", "sim n", "sim ok [%]", "sim 95% CI [%]", "sim err med [mm]"):
        v.add_column(col, justify="left" if col in ("tool", "variant") else "right")
    for s in stats:
        v.add_row(s.tool, s.variant, _fmt(s.cone_violation_max, 1, 3), _fmt(s.reach_violation_max, 1e3),
                  _fmt(s.penetration_max, 1e3), _fmt(s.joint_limit_violation_max, 1, 3),
                  _fmt(s.obstacle_clearance_min, 1e3), _fmt(s.goal_error_max, 1e3), str(s.sim_n),
                  _fmt(s.sim_rate, 100, 1), f"{_fmt(s.sim_ci_low, 100, 1)}-{_fmt(s.sim_ci_high, 100, 1)}",
                  _fmt(s.sim_final_error_median, 1e3, 1))
    console.print(v)
    if reasons:
        r = Table(title="top reasons (numbers shown as #)")
        for col in ("variant", "status", "count", "reason"):
            r.add_column(col, justify="right" if col == "count" else "left")
        for e in reasons:
            r.add_row(e["variant"], e["status"], str(e["count"]), e["reason"])
        console.print(r)


def write_csv(path: Path, rows: Sequence[dict[str, Any]], columns: Sequence[str] | None = None) -> Path:
    """Write ``rows`` as CSV (``columns`` default: the first row's keys)."""
    cols = list(columns) if columns is not None else (list(rows[0]) if rows else [])
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    return path


def write_report(db: str | Path, out: str | Path | None, console: Console | None = None) -> list[Path]:
    """Print the report of the store ``db``; with ``out``, write ``results.csv``, ``summary.csv``,
    ``reasons.csv`` and the figures there. Returns the written paths."""
    from dmp.errors import InputError
    from planner.batch.store import ResultStore

    p = Path(db)
    if not p.is_file():
        raise InputError("db", "an existing results file (written by tooltransfer batch run)", str(p))
    if console is None:
        console = Console()
        if not console.is_terminal:
            console.width = 180  # files and pipes: whole tables
    with ResultStore(p) as store:
        rows = store.rows()
        meta = store.meta()
    if not rows:
        console.print(f"{p}: no results yet")
        return []
    stats = summarize(rows)
    reasons = top_reasons(rows)
    console.print(f"batch {meta.get('batch_name', '?')}: {len(rows)} results in {p}")
    print_report(stats, reasons, console)
    if out is None:
        return []
    folder = Path(out)
    written = [write_csv(folder / "results.csv", [{**r, "valid": int(is_valid(r))} for r in rows]),
               write_csv(folder / "summary.csv", [asdict(s) for s in stats], [f.name for f in fields(GroupStats)]),
               write_csv(folder / "reasons.csv", reasons, ["variant", "status", "count", "reason"])]
    from planner.batch.figures import plot_batch

    written += plot_batch(rows, folder)
    return written
