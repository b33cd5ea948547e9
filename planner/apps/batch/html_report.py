"""``report.html``: a batch's results as one self-contained page (``batch report DB --out DIR``).

What it shows, from the store's rows and tasks:

- per tool and variant, the success rate (solved) with its 95% Wilson interval, and the verdicts
  (solved, certified infeasible, unknown: violated included, error, timeout) as a table and a plot;
- every distinct reason in full per variant and failing status, with its count
  (:func:`~tooltransfer.planner.apps.batch.report.all_reasons`);
- the planning times and the goal and executed errors as interactive distributions (hover names
  the task);
- a table of every task and variant, sortable (click a header) and filtered by text, status,
  variant and tool;
- a task panel: a row's click draws its task (start, target, obstacles) with every variant's
  planned object path (``metrics_json["object_path"]``, :func:`~tooltransfer.planner.apps.batch.execute.path_outline`)
  and lists the variants' verdicts and reasons.

The plots are Bokeh models (:mod:`tooltransfer.planner.apps.plots.html_page`: Bokeh inlined, no
network at view time); the table's filter, sort and the panel's update are a short script
(:data:`~tooltransfer.planner.apps.batch.html_script.TABLE_JS`). Values are shown in the display units
of :mod:`tooltransfer.planner.common.metric_units` (lengths in mm, times in ms) and named so.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tooltransfer.planner.apps.batch.html_plots import VARIANT_COLOURS, error_plot, panel_plot, rate_plot, time_plot
from tooltransfer.planner.apps.batch.html_script import TABLE_CSS, TABLE_JS
from tooltransfer.planner.apps.plots.html_page import esc, json_script, plot, require_bokeh, write_page

#: The task table's columns: header, row key, shown unit's scale (None: text), digits.
TABLE_COLUMNS: tuple[tuple[str, str, float | None, int], ...] = (
    ("task", "task_id", None, 0), ("tool", "tool", None, 0), ("variant", "variant", None, 0),
    ("status", "status", None, 0), ("obstacles", "n_obstacles", 1.0, 0), ("reach margin [mm]", "reach_margin", 1e3, 1),
    ("time [ms]", "time_total", 1e3, 0), ("goal err [mm]", "goal_error", 1e3, 2),
    ("OL err [mm]", "open_loop_error", 1e3, 2), ("CL", "closed_loop_status", None, 0),
    ("CL err [mm]", "closed_loop_error", 1e3, 2), ("reason", "reason", None, 0),
)


#: Widths of the task table's columns [px] (a fixed layout: filtering does not measure every cell).
COLUMN_WIDTHS = (120, 60, 125, 85, 80, 70, 60, 60, 60, 60, 60, 370)
#: Rows drawn at a time (the script's page, :data:`~tooltransfer.planner.apps.batch.html_script.TABLE_JS`).
PAGE_ROWS = 100


def _num(v: Any, scale: float, digits: int) -> tuple[str, str]:
    """The cell text and sort key of a number (``""`` and ``""`` for a missing one)."""
    if v is None or isinstance(v, str):
        return "", ""
    f = float(v) * scale
    if not math.isfinite(f):
        return "", ""
    return f"{f:.{digits}f}", repr(f)


def _pct(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{100 * v:.1f}"


def _row_reason(r: dict[str, Any]) -> str:
    """A row's reason: its planning reason, or for a solved plan its executions' failures."""
    if r["status"] != "solved":
        return r.get("reason") or ""
    parts = [f"{loop}: {r.get(f'{key}_reason')}" for key, loop in (("open_loop", "open loop"),
                                                                   ("closed_loop", "closed loop"))
             if r.get(f"{key}_status") not in (None, "done", "reached") and r.get(f"{key}_reason")]
    return "; ".join(parts)


def task_table(rows: Sequence[dict[str, Any]]) -> str:
    """The ``<table id="rows">`` of every row (module docstring)."""
    head = "".join(f'<th class="{"text" if scale is None else "num"}">{esc(h)}</th>'
                   for h, _, scale, _ in TABLE_COLUMNS)
    hidden = ' style="display:none"'  # beyond the first page (the script draws a page at a time)
    cols = "".join(f'<col style="width:{w}px">' for w in COLUMN_WIDTHS)
    out = [f'<table class="data" id="rows" data-page="{PAGE_ROWS}" '
           f'style="width:{sum(COLUMN_WIDTHS)}px"><colgroup>{cols}</colgroup>'
           f"<thead><tr>{head}</tr></thead><tbody>"]
    for i, r in enumerate(rows):
        cells = []
        for _, key, scale, digits in TABLE_COLUMNS:
            if scale is None:
                text = _row_reason(r) if key == "reason" else str(r.get(key) or "")
                cls = "reason" if key == "reason" else f"text s-{esc(text)}" if key == "status" else "text"
                cells.append(f'<td class="{cls}">{esc(text)}</td>')
            else:
                text, sort = _num(r.get(key), scale, digits)
                cells.append(f'<td data-v="{sort}">{text}</td>')
        out.append(f'<tr data-task="{esc(r["task_id"])}" data-status="{esc(r["status"])}" '
                   f'data-variant="{esc(r["variant"])}" data-tool="{esc(r.get("tool") or "")}"'
                   f'{hidden if i >= PAGE_ROWS else ""}>{"".join(cells)}</tr>')
    out.append("</tbody></table>")
    return "".join(out)


def summary_table(stats: Sequence[Any]) -> str:
    """Per tool and variant (``stats``: :func:`~tooltransfer.planner.apps.batch.report.summarize`'s
    ``GroupStats``): counts, the rates with their 95% Wilson intervals (and how many unknowns stopped on
    the search's or the certificate's budget: ``--retry unknown --budget K`` may decide those), planning
    times."""
    head = ("tool", "variant", "n", "solved", "rate [%]", "95% CI [%]", "infeasible", "95% CI [%]", "unknown",
            "95% CI [%]", "unknown on a budget", "violated", "error", "timeout", "t50 [ms]", "t90 [ms]", "t99 [ms]")
    out = ['<table class="data" id="summary"><thead><tr>',
           "".join(f'<th class="{"text" if h in ("tool", "variant") else "num"}">{esc(h)}</th>' for h in head),
           "</tr></thead><tbody>"]
    for s in stats:
        vals = (s.tool, s.variant, s.n, s.solved, _pct(s.rate), f"{_pct(s.ci_low)}-{_pct(s.ci_high)}", s.infeasible,
                f"{_pct(s.infeasible_ci_low)}-{_pct(s.infeasible_ci_high)}", s.unknown,
                f"{_pct(s.unknown_ci_low)}-{_pct(s.unknown_ci_high)}", s.unknown_on_budget, s.violated, s.error,
                s.timeout,
                *(("-" if not math.isfinite(t) else f"{1e3 * t:.0f}") for t in (s.time_p50, s.time_p90, s.time_p99)))
        out.append("<tr>" + "".join(f'<td class="{"text" if i < 2 else "num"}">{esc(v)}</td>'
                                    for i, v in enumerate(vals)) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def reasons_table(reasons: Sequence[dict[str, Any]]) -> str:
    """Every distinct reason in full, per variant and failing status, with its count (``reasons``:
    :func:`~tooltransfer.planner.apps.batch.report.all_reasons`)."""
    out = ['<table class="data" id="reasons"><thead><tr><th class="text">variant</th><th class="text">status</th>'
           '<th>count</th><th class="text">reason</th></tr></thead><tbody>']
    for e in reasons:
        out.append(f'<tr><td class="text">{esc(e["variant"])}</td><td class="text s-{esc(e["status"])}">'
                   f'{esc(e["status"])}</td><td>{e["count"]}</td><td class="reason">{esc(e["reason"])}</td></tr>')
    out.append("</tbody></table>")
    return "".join(out)


def task_panels(rows: Sequence[dict[str, Any]], tasks: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Per task: its scene (start, target, puck radius, obstacles) [m] and per variant the status,
    the full reason and the planned object path ``[[x...], [y...]]`` [m] where the row kept one."""
    out: dict[str, Any] = {}
    for r in rows:
        tid = r["task_id"]
        if tid not in out:
            t = tasks.get(tid, {})
            obs = []
            for o in t.get("obstacles") or []:
                if o.get("kind") == "polygon":
                    obs.append({"v": o.get("vertices")})
                else:
                    obs.append({"c": o.get("centre"), "r": o.get("radius")})
            out[tid] = {"start": t.get("start"), "target": t.get("target"),
                        "r": (t.get("object") or {}).get("radius", 0.0175), "obs": obs, "v": {}}
        try:
            path = json.loads(r.get("metrics_json") or "{}").get("object_path") or []
        except (ValueError, AttributeError):
            path = []
        out[tid]["v"][r["variant"]] = {"status": r["status"], "reason": _row_reason(r),
                                       "path": [[p[0] for p in path], [p[1] for p in path]]}
    return out


def write_html_report(rows: Sequence[dict[str, Any]], stats: Sequence[Any], reasons: Sequence[dict[str, Any]],
                      meta: dict[str, str], tasks: dict[str, dict[str, Any]], path: Path) -> Path:
    """Write ``report.html`` (module docstring) to ``path``: of the store's ``rows``, their ``stats``
    (:func:`~tooltransfer.planner.apps.batch.report.summarize`), every reason
    (:func:`~tooltransfer.planner.apps.batch.report.all_reasons`), the store's ``meta`` and its
    ``tasks`` by id; returns it."""
    require_bokeh()

    variants = sorted({r["variant"] for r in rows})
    colours = {v: VARIANT_COLOURS[i % len(VARIANT_COLOURS)] for i, v in enumerate(variants)}
    models = [rate_plot(stats), time_plot(rows, variants), error_plot(rows, variants, colours), panel_plot()]
    name = meta.get("batch_name", "?")
    options = {k: sorted({str(r.get(k) or "") for r in rows}) for k in ("status", "variant", "tool")}
    selects = "".join(f'<label>{k} <select id="f-{k}"><option value="">all</option>'
                      + "".join(f'<option value="{esc(v)}">{esc(v)}</option>' for v in vals)
                      + "</select></label> " for k, vals in options.items())
    body = (f"<h1>Batch {esc(name)}: {len(rows)} results, {len({r['task_id'] for r in rows})} tasks, "
            f"{len(variants)} variants</h1>"
            '<p class="note">Success: a solved plan (every hard check holds). Infeasible: certified (a certificate '
            "proves no plan exists under its rules). Unknown: neither (violated plans included). "
            "Intervals: 95% Wilson. Lengths in mm, times in ms; the CSV files beside this page hold the same "
            "values in SI units.</p>"
            "<h2>Success and verdicts per tool and variant</h2>" + summary_table(stats) + plot("rates")
            + "<h2>Distributions</h2><div class=\"row\">" + plot("times") + plot("errors") + "</div>"
            + "<h2>Every task and variant</h2>"
            f'<div class="filters"><label>filter <input id="f-text" type="search" placeholder="text in any column">'
            f"</label> {selects}<button id=\"prev\">previous</button> <button id=\"next\">next</button> "
            '<span id="count"></span></div>'
            '<div class="row"><div class="scroll">' + task_table(rows) + '</div><div id="panel">'
            '<h3 id="panel-title">task</h3>' + plot("panel") + '<div id="panel-text"></div></div></div>'
            "<h2>Reasons in full</h2>" + reasons_table(reasons)
            + json_script("tasks", task_panels(rows, tasks)) + json_script("colours", colours))
    return write_page(path, f"batch {name}", body, models, css=TABLE_CSS, script=TABLE_JS)
