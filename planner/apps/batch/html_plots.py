"""The Bokeh plots of ``report.html`` (:mod:`tooltransfer.planner.apps.batch.html_report`): success
rates with their Wilson intervals, planning times, errors, and the task panel's empty scene (filled by
the page's script from the task data). Each plot is named, so the page lays it out by name and its
script finds its data sources (``panel_*``) by name. Shown units: lengths in mm, times in ms."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

#: Colours of the statuses in plots (the table's classes use the same hues).
STATUS_COLOURS = {"solved": "#1a7f37", "infeasible": "#8250df", "unknown": "#bc4c00", "violated": "#fb8500",
                  "error": "#cf222e", "timeout": "#6e7781"}
#: Colours of the variants (Bokeh's Category10).
VARIANT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                   "#bcbd22", "#17becf")
_STATUSES = ("solved", "violated", "infeasible", "unknown", "error", "timeout")


def rate_plot(stats: Sequence[Any]) -> Any:
    """Success rate per tool and variant (dots) with 95% Wilson intervals (whiskers; ``stats``:
    :func:`~tooltransfer.planner.apps.batch.report.summarize`'s); hover gives the counts."""
    from bokeh.models import ColumnDataSource, HoverTool, Whisker
    from bokeh.plotting import figure

    labels = [f"{s.tool} {s.variant}" for s in stats]
    src = ColumnDataSource({"label": labels, "rate": [100 * s.rate for s in stats],
                            "lo": [100 * s.ci_low if math.isfinite(s.ci_low) else 0.0 for s in stats],
                            "hi": [100 * s.ci_high if math.isfinite(s.ci_high) else 0.0 for s in stats],
                            "n": [s.n for s in stats], "solved": [s.solved for s in stats],
                            "infeasible": [s.infeasible for s in stats], "unknown": [s.unknown for s in stats]})
    p = figure(name="rates", y_range=list(reversed(labels)), x_range=(0, 100), width=640,
               height=60 + 26 * len(labels), title="success rate per tool and variant, 95% Wilson interval",
               x_axis_label="solved [%]", toolbar_location=None)
    p.add_layout(Whisker(source=src, base="label", lower="lo", upper="hi", dimension="width"))
    p.scatter("rate", "label", source=src, size=9)
    p.add_tools(HoverTool(tooltips=[("", "@label"), ("solved", "@solved of @n (@rate{0.0} %)"),
                                    ("95% CI", "@lo{0.0}-@hi{0.0} %"), ("infeasible", "@infeasible"),
                                    ("unknown", "@unknown")]))
    return p


def time_plot(rows: Sequence[dict[str, Any]], variants: Sequence[str]) -> Any:
    """Planning time of every row (log scale) per variant, coloured by status, jittered; hover names
    the task."""
    from bokeh.models import ColumnDataSource, HoverTool
    from bokeh.plotting import figure
    from bokeh.transform import jitter

    p = figure(name="times", y_range=list(reversed(variants)), x_axis_type="log", width=620,
               height=120 + 60 * len(variants), title="planning time per variant (every task; hover for the task)",
               x_axis_label="planning time [ms] (log)", tools="pan,wheel_zoom,box_zoom,reset,save")
    for status in _STATUSES:
        sub = [r for r in rows if r["status"] == status and r.get("time_total")]
        if not sub:
            continue
        src = ColumnDataSource({"t": [1e3 * float(r["time_total"]) for r in sub], "v": [r["variant"] for r in sub],
                                "task": [r["task_id"] for r in sub], "status": [status] * len(sub)})
        p.scatter("t", jitter("v", 0.5, range=p.y_range), source=src, size=4, alpha=0.6,
                  color=STATUS_COLOURS[status], legend_label=f"{status} ({len(sub)})")
    if not p.renderers:  # no timed row: an empty plot, said so
        p.scatter([], [])
        p.title.text += ": no timed rows"
    p.add_tools(HoverTool(tooltips=[("task", "@task"), ("variant", "@v"), ("status", "@status"),
                                    ("time", "@t{0.0} ms")]))
    if p.legend:
        p.legend.click_policy = "hide"
        p.legend.location = "top_left"
    return p


def error_plot(rows: Sequence[dict[str, Any]], variants: Sequence[str], colours: dict[str, str]) -> Any:
    """Cumulative distributions of the solved plans' goal error and, where plans were executed, the
    open- and closed-loop final errors, per variant (log scale)."""
    from bokeh.models import ColumnDataSource, HoverTool
    from bokeh.plotting import figure

    p = figure(name="errors", x_axis_type="log", width=620, height=360, y_range=(0, 1.02),
               title="errors of solved plans: share at or below (goal solid, open loop dashed, closed loop dotted)",
               x_axis_label="error [mm] (log)", y_axis_label="share of solved plans",
               tools="pan,wheel_zoom,box_zoom,reset,save")
    for v in variants:
        ok = [r for r in rows if r["variant"] == v and r["status"] == "solved"]
        for key, dash, name in (("goal_error", "solid", "goal"), ("open_loop_error", "dashed", "OL"),
                                ("closed_loop_error", "dotted", "CL")):
            pairs = sorted((1e3 * float(r[key]), r["task_id"]) for r in ok if r.get(key) is not None)
            if not pairs:
                continue
            err = [max(e, 1e-4) for e, _ in pairs]
            share = [(i + 1) / len(ok) for i in range(len(pairs))]
            src = ColumnDataSource({"e": err, "s": share, "task": [t for _, t in pairs]})
            p.step("e", "s", source=src, mode="after", line_dash=dash, color=colours[v],
                   legend_label=f"{v} {name} ({len(pairs)})")
            p.scatter("e", "s", source=src, size=3, color=colours[v])
    if not p.renderers:  # no solved plan with an error: an empty plot, said so
        p.scatter([], [])
        p.title.text = "errors of solved plans: none measured"
    p.add_tools(HoverTool(tooltips=[("task", "@task"), ("error", "@e{0.000} mm"), ("share", "@s{0.00}")]))
    if p.legend:
        p.legend.click_policy = "hide"
        p.legend.location = "bottom_right"
        p.legend.label_text_font_size = "8pt"
    return p


def panel_plot() -> Any:
    """The task panel's scene: empty sources named ``panel_discs`` (obstacle discs), ``panel_polys``
    (obstacle polygons), ``panel_pucks`` (the puck at start and target), ``panel_paths`` (one
    planned object path per variant), filled by the page's script; axes in mm."""
    from bokeh.models import ColumnDataSource, HoverTool
    from bokeh.plotting import figure

    p = figure(name="panel", width=420, height=420, match_aspect=True, x_axis_label="x [mm]", y_axis_label="y [mm]",
               tools="pan,wheel_zoom,reset,save", title="planned object paths")
    discs = ColumnDataSource({"x": [], "y": [], "r": []}, name="panel_discs")
    polys = ColumnDataSource({"xs": [], "ys": []}, name="panel_polys")
    pucks = ColumnDataSource({"x": [], "y": [], "r": [], "c": [], "what": []}, name="panel_pucks")
    paths = ColumnDataSource({"xs": [], "ys": [], "c": [], "variant": [], "status": []}, name="panel_paths")
    p.circle("x", "y", radius="r", source=discs, color="#555", alpha=0.6)
    p.patches("xs", "ys", source=polys, color="#555", alpha=0.6)
    p.circle("x", "y", radius="r", source=pucks, fill_alpha=0.15, line_color="c", fill_color="c", line_width=2)
    lines = p.multi_line("xs", "ys", source=paths, line_color="c", line_width=2, legend_field="variant")
    p.add_tools(HoverTool(renderers=[lines], tooltips=[("variant", "@variant"), ("status", "@status")]))
    p.legend.location = "top_left"
    p.legend.label_text_font_size = "8pt"
    return p
