"""A tool choice in words: the reason shown beside each candidate, the JSON summary of
``tooltransfer choose --json`` and its table.

The summary: ``{"task", "verdict", "best", "plan", "figure", "wall_time", "cpu_time", "ranking": [...]}``,
one ranking entry per candidate, best first: ``rank``, ``tool`` (as named), ``name`` (the tool's own),
``verdict`` (``solved|infeasible|unknown``), ``reason``, ``stopped`` (whether its planning was stopped
once another plan had passed every execution: then ``unknown``), ``executed`` (whether its plan was executed),
the final errors [m] ``open_loop_error``, ``closed_loop_error``, ``mismatch_closed_loop_error`` and the
closed loops' statuses, the margins ``friction_cone_margin`` [rad], ``contact_edge_margin`` [m],
``clearance`` [m] (null: infinite, no obstacle), ``margin_score``, ``duration`` [s] and
``planning_time`` [s] (wall).
"""

from __future__ import annotations

import math
from typing import Any

from tooltransfer.planner.apps.choose.ranking import EXECUTIONS, TOLERANCES, margin_score, margins, weakest_margin
from tooltransfer.planner.apps.choose.run import Choice, Ranked

_NAMES = {"open_loop": "open loop", "closed_loop": "closed loop", "mismatch_closed_loop": "mismatched closed loop"}
_MARGIN_WORDS = {"friction_cone": "friction cone", "contact_edge": "contact edge", "clearance": "clearance"}


def _mm(v: float | None) -> str:
    return "-" if v is None else f"{1e3 * v:.2f} mm"


def _margin_text(r: Ranked) -> str:
    m = margins(r.plan.metrics) if r.plan is not None else {}
    k = weakest_margin(r.plan.metrics) if r.plan is not None else "friction_cone"
    v = m.get(k, 0.0)
    return f"weakest margin {_MARGIN_WORDS[k]} " + (f"{v:.3f} rad" if k == "friction_cone" else _mm(v))


def reason(r: Ranked, best: Ranked | None) -> str:
    """Why the candidate stands where it does, in one line."""
    if r.verdict != "solved":
        return r.reason or r.verdict
    if r.executions is None:
        if not r.runs and best is not None and best is not r:
            return f"not executed ({best.label} ranks above by margins and passed every execution); " \
                   + _margin_text(r)
        return "not executed; " + _margin_text(r)
    failed = [f"{_NAMES[k]} {_mm(getattr(r.executions, k))} > {1e3 * TOLERANCES[k]:g} mm"
              + (f" ({r.runs[k].status})" if k in r.runs and r.runs[k].status not in ("done", "reached") else "")
              for k, ok in zip(EXECUTIONS, r.executions.passes(), strict=True) if not ok]
    head = "failed: " + "; ".join(failed) if failed else "passed every execution"
    return f"{head}; {_margin_text(r)}"


def _finite(v: float | None) -> float | None:
    return v if v is not None and math.isfinite(v) else None


def entry(r: Ranked, best: Ranked | None) -> dict[str, Any]:
    """The JSON entry of one candidate (module docstring)."""
    m = r.plan.metrics if r.plan is not None and r.verdict == "solved" else {}
    g = margins(m) if m else {}
    ex = r.executions
    out: dict[str, Any] = {
        "rank": r.rank, "tool": r.label, "name": r.tool, "verdict": r.verdict, "reason": reason(r, best),
        "stopped": r.stopped, "executed": ex is not None,
        "open_loop_error": ex.open_loop if ex else None, "closed_loop_error": ex.closed_loop if ex else None,
        "mismatch_closed_loop_error": ex.mismatch_closed_loop if ex else None,
        "closed_loop_status": r.runs["closed_loop"].status if "closed_loop" in r.runs else None,
        "mismatch_closed_loop_status": r.runs["mismatch_closed_loop"].status
        if "mismatch_closed_loop" in r.runs else None,
        "friction_cone_margin": _finite(g.get("friction_cone")), "contact_edge_margin": _finite(g.get("contact_edge")),
        "clearance": _finite(g.get("clearance")), "margin_score": margin_score(m) if m else None,
        "duration": _finite(m.get("duration")) if m else None, "planning_time": r.planning_wall,
    }
    return out


def summary(choice: Choice, plan_path: str | None = None, figure: str | None = None) -> dict[str, Any]:
    """The JSON summary of a choice (module docstring)."""
    best = choice.best
    return {"task": choice.task.name, "verdict": choice.verdict, "best": best.label if best else None,
            "plan": plan_path, "figure": figure, "wall_time": choice.wall, "cpu_time": choice.cpu,
            "ranking": [entry(r, best) for r in choice.ranking]}


def table(choice: Choice) -> Any:
    """A rich table of the ranking: rank, tool, verdict, the executions' final errors [mm], the
    weakest margin's score, the duration [s] and the reason."""
    from rich import box
    from rich.markup import escape
    from rich.table import Table

    best = choice.best
    t = Table(title=f"{escape(choice.task.name)}: " + (f"best tool {escape(best.label)}" if best else
                                                        f"no tool solves it ({choice.verdict})"),
              title_justify="left", box=box.SIMPLE_HEAD)
    for col in ("rank", "tool", "verdict", "closed mm", "mismatch mm", "open mm", "margin", "duration s", "reason"):
        t.add_column(col, justify="right" if col not in ("tool", "verdict", "reason") else "left",
                     overflow="fold", no_wrap=col != "reason", ratio=1 if col == "reason" else None)
    for r in choice.ranking:
        e = entry(r, best)

        def mm(k: str, e: dict[str, Any] = e) -> str:
            return "-" if e[k] is None else f"{1e3 * e[k]:.2f}"

        t.add_row(str(r.rank), escape(r.label), r.verdict, mm("closed_loop_error"), mm("mismatch_closed_loop_error"),
                  mm("open_loop_error"), "-" if e["margin_score"] is None else f"{e['margin_score']:.2f}",
                  "-" if e["duration"] is None else f"{e['duration']:.1f}", escape(e["reason"]))
    return t
