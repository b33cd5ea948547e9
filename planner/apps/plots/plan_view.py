"""``tooltransfer view PLAN.json -o plan.html``: a plan as one self-contained interactive page.

The table seen from above (x, y in mm): obstacles, the puck at start and target, the planned object
path and tool path, each push's start (its face), each switch (``from -> to``, a face change) and
re-contact (a switch back onto the same face) marked where the object was then; the tool's outline,
the face in contact (during a push) and the puck animated along the plan with a time slider and a
play button. With a recording (:mod:`tooltransfer.planner.execution.recording`: ``simulate --record``)
the executed object and tool paths are drawn beside the planned ones, and the executed puck moves
with the same slider.

Built as a Plotly figure (data, layout, animation frames) written as JSON beside ``plotly.min.js``
inlined from the installed ``plotly`` package (its Python code is never imported: the page is
quick to write). The layout's ``meta`` holds the plan sample index of each frame
(``frame_index``) and the puck trace's index (``puck_trace``), for a reader of the page (the browser
test moves the slider and compares the puck with the plan file).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.plan import Plan

#: Most animation frames (evenly spaced plan samples, the first and last kept).
MAX_FRAMES = 240
_MM = 1e3
_CIRCLE = np.linspace(0.0, 2.0 * np.pi, 41)


def plotly_js() -> str:
    """The text of ``plotly.min.js`` from the installed ``plotly`` package.

    Raises:
        ModuleNotFoundError: plotly is not installed (``pip install "tooltransfer[report]"``).
    """
    spec = importlib.util.find_spec("plotly")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError('the plan viewer needs plotly (its plotly.min.js): pip install '
                                  '"tooltransfer[report]" (or pip install plotly)', name="plotly")
    path = Path(next(iter(spec.submodule_search_locations))) / "package_data" / "plotly.min.js"
    if not path.is_file():
        raise ImportError(f"the installed plotly has no {path.name} at {path.parent}: reinstall plotly")
    return path.read_text(encoding="utf-8")


def _circle(c: NDArray[np.float64] | list[float], r: float) -> tuple[list[float], list[float]]:
    x, y = (c[0] + r * np.cos(_CIRCLE)) * _MM, (c[1] + r * np.sin(_CIRCLE)) * _MM
    return x.round(3).tolist(), y.round(3).tolist()


def _outline(outline: NDArray[np.float64], pose: NDArray[np.float64]) -> tuple[list[float], list[float]]:
    """The tool's closed outline (tool frame, (K, 2) [m]) at ``pose`` (x, y, yaw) in mm."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    w = outline @ np.array([[c, s], [-s, c]]) + pose[:2]
    w = np.vstack([w, w[:1]]) * _MM
    return w[:, 0].round(3).tolist(), w[:, 1].round(3).tolist()


def _face(plan: Plan, k: int) -> tuple[list[float | None], list[float | None]]:
    """The face in contact at sample ``k`` (a push) as a segment in mm, or nothing."""
    name = plan.face[k] if k < len(plan.face) else None
    if plan.phase[k] != "push" or name is None:
        return [None], [None]
    seg = next((np.asarray(f["segment"], dtype=float) for f in plan.tool.get("faces", []) if f.get("name") == name),
               None)
    if seg is None:
        return [None], [None]
    x, y = _outline(seg, plan.tool_pose[k])
    return list(x[:2]), list(y[:2])


def _line(name: str, xy: Any, **style: Any) -> dict[str, Any]:
    a = np.asarray(xy, dtype=float).reshape(-1, 2) * _MM
    return {"type": "scatter", "mode": "lines", "name": name, "x": a[:, 0].round(3).tolist(),
            "y": a[:, 1].round(3).tolist(), **style}


def _at(t: NDArray[np.float64], series: NDArray[np.float64], when: float) -> NDArray[np.float64]:
    """``series`` (N, D) at time ``when`` (linear between samples, held at the ends)."""
    return np.array([np.interp(when, t, series[:, j]) for j in range(series.shape[1])])


def _events(plan: Plan) -> list[dict[str, Any]]:
    """Markers of the pushes' starts, the switches and the re-contacts, at the object's position."""
    def where(t: float) -> NDArray[np.float64]:
        return _at(plan.t, plan.object_xy, t) * _MM

    out = []
    for kind, segs, symbol, colour in (("push", plan.pushes, "triangle-up", "#1a7f37"),
                                      ("switch", plan.switches, "diamond", "#d62728")):
        pts, text = [], []
        recontacts, rtext = [], []
        for s in segs:
            p = where(s.t_start)
            if kind == "switch" and len(s.faces) == 2 and s.faces[0] == s.faces[1]:
                recontacts.append(p)
                rtext.append(f"re-contact on {s.faces[0]} at {s.t_start:.2f} s")
            else:
                pts.append(p)
                text.append(f"push on {s.faces[0]} from {s.t_start:.2f} s" if kind == "push" else
                            f"switch {' -> '.join(s.faces)} at {s.t_start:.2f} s")
        for name, ps, tx, sym, col in ((f"{kind}es" if kind == "push" else "switches", pts, text, symbol, colour),
                                       ("re-contacts", recontacts, rtext, "x", "#fb8500")):
            if ps:
                a = np.array(ps)
                out.append({"type": "scatter", "mode": "markers", "name": f"{name} ({len(ps)})",
                            "x": a[:, 0].round(3).tolist(), "y": a[:, 1].round(3).tolist(), "text": tx,
                            "hoverinfo": "text", "marker": {"symbol": sym, "size": 11, "color": col}})
    return out


def view_figure(plan: Plan, executions: dict[str, dict[str, Any]] | None = None) -> dict[str, Any]:
    """The Plotly figure (``data``, ``layout``, ``frames``) of ``plan`` and its ``executions``
    (:func:`tooltransfer.planner.execution.recording.read_recording`)."""
    r = float(plan.object["radius"])
    start, goal = plan.object.get("start", plan.task.get("start")), plan.object.get("goal", plan.task.get("target"))
    outline = np.asarray(plan.tool["outline"], dtype=float)
    data: list[dict[str, Any]] = []
    for i, o in enumerate(plan.obstacles):
        x, y = (_circle(o["centre"], float(o["radius"])) if o.get("kind") == "disc" else
                _outline(np.asarray(o["vertices"], dtype=float), np.zeros(3)))
        data.append({"type": "scatter", "mode": "lines", "fill": "toself", "name": "obstacles", "x": x, "y": y,
                     "line": {"color": "#555"}, "fillcolor": "rgba(80,80,80,0.45)", "legendgroup": "obstacles",
                     "showlegend": i == 0, "hoverinfo": "name"})
    for name, c, dash in (("start", start, "solid"), ("target", goal, "dash")):
        if c is not None:
            x, y = _circle(c, r)
            data.append({"type": "scatter", "mode": "lines", "name": name, "x": x, "y": y, "hoverinfo": "name",
                         "line": {"color": "#d62728" if name == "target" else "#888", "dash": dash}})
    n = len(plan.t)
    if n:
        data.append(_line("planned object path", plan.object_xy, line={"color": "#1f77b4", "width": 2}))
        data.append(_line("planned tool path", plan.tool_pose[:, :2], line={"color": "#7f7f7f", "dash": "dot"}))
        data += _events(plan)
    runs = executions or {}
    colours = {"open loop": "#ff7f0e", "closed loop": "#9467bd"}
    for mode, e in runs.items():
        c = colours.get(mode, "#2ca02c")
        data.append(_line(f"executed object path, {mode}", e["object_xy"], line={"color": c, "width": 2}))
        data.append(_line(f"executed tool path, {mode}", np.asarray(e["tool_pose"])[:, :2],
                          line={"color": c, "dash": "dot", "width": 1}))
    frames: list[dict[str, Any]] = []
    meta: dict[str, Any] = {"frame_index": [], "puck_trace": None}
    if n:
        idx = np.linspace(0, n - 1, min(n, MAX_FRAMES)).round().astype(int)
        idx = idx[np.r_[True, idx[1:] != idx[:-1]]]  # non-decreasing: np.unique, without its import of numpy.ma
        first = len(data)
        meta.update(frame_index=idx.tolist(), puck_trace=first)
        tool_style = {"mode": "lines", "fill": "toself", "line": {"color": "#222"},
                      "fillcolor": "rgba(31,119,180,0.35)"}

        def moving(k: int) -> list[dict[str, Any]]:
            tx, ty = _outline(outline, plan.tool_pose[k])
            fx, fy = _face(plan, k)
            px, py = _circle(plan.object_xy[k], r)
            out: list[dict[str, Any]] = [{"type": "scatter", "x": px, "y": py}, {"type": "scatter", "x": tx, "y": ty},
                   {"type": "scatter", "x": fx, "y": fy}]
            for e in runs.values():
                ex, ey = _circle(_at(np.asarray(e["t_object"]), np.asarray(e["object_xy"]), float(plan.t[k])), r)
                out.append({"type": "scatter", "x": ex, "y": ey})
            return out

        start_traces = moving(int(idx[0]))
        names = ["puck (plan)", "tool", "face in contact", *(f"puck, {m}" for m in runs)]
        styles = [{"mode": "lines", "fill": "toself", "line": {"color": "#1f77b4"},
                   "fillcolor": "rgba(31,119,180,0.2)"},
                  tool_style, {"mode": "lines", "line": {"color": "#d62728", "width": 5}},
                  *({"mode": "lines", "line": {"color": colours.get(m, "#2ca02c"), "dash": "dash"}} for m in runs)]
        for trace, name, style in zip(start_traces, names, styles, strict=True):
            data.append({**trace, **style, "name": name, "hoverinfo": "name"})
        traces = list(range(first, len(data)))
        for k in idx:
            frames.append({"name": str(int(k)), "data": moving(int(k)), "traces": traces,
                           "layout": {"title": {"text": _title(plan, int(k))}}})
    anim = {"mode": "immediate", "frame": {"duration": 0, "redraw": False}, "transition": {"duration": 0}}
    layout: dict[str, Any] = {
        "title": {"text": _title(plan, 0) if n else f"{plan.task.get('name', 'plan')}: {plan.status}, no path"},
        "xaxis": {"title": {"text": "x [mm]"}, "scaleanchor": "y", "scaleratio": 1},
        "yaxis": {"title": {"text": "y [mm]"}}, "height": 760, "hovermode": "closest", "meta": meta,
        "legend": {"font": {"size": 11}}, "margin": {"t": 60, "b": 140},
    }
    if frames:
        layout["sliders"] = [{
            "active": 0, "currentvalue": {"prefix": "t = ", "suffix": " s"}, "pad": {"t": 40},
            "steps": [{"label": f"{plan.t[int(f['name'])]:.2f}", "method": "animate", "args": [[f["name"]], anim]}
                      for f in frames]}]
        layout["updatemenus"] = [{
            "type": "buttons", "direction": "left", "x": 0.0, "y": -0.08, "xanchor": "left", "yanchor": "top",
            "buttons": [{"label": "play", "method": "animate",
                         "args": [None, {"frame": {"duration": 60, "redraw": False}, "fromcurrent": True,
                                         "transition": {"duration": 0}}]},
                        {"label": "pause", "method": "animate", "args": [[None], anim]}]}]
    return {"data": data, "layout": layout, "frames": frames}


def _title(plan: Plan, k: int) -> str:
    phase = plan.phase[k] if k < len(plan.phase) else ""
    face = plan.face[k] if k < len(plan.face) and plan.face[k] else ""
    name = plan.task.get("name", "plan")
    return f"{name} ({plan.variant.get('oe', '?')}/{plan.variant.get('ss', '?')}, {plan.status}): " \
           f"t = {plan.t[k]:.2f} s, {phase}{' on ' + face if face and phase == 'push' else ''}"


def write_plan_view(plan: Plan, out: str | Path, executions: dict[str, dict[str, Any]] | None = None,
                    title: str = "plan") -> Path:
    """Write the page of ``plan`` (and its ``executions``) to ``out`` atomically; returns it."""
    from tooltransfer.atomic import write_text
    from tooltransfer.planner.apps.plots.html_page import esc, script_json

    fig = script_json(view_figure(plan, executions))
    m = plan.metrics
    facts = ", ".join(f"{k} {v}" for k, v in (
        ("duration", f"{m['duration']:.2f} s" if isinstance(m.get("duration"), float) else None),
        ("pushes", len(plan.pushes) or None), ("switches", len(plan.switches) or None),
        ("re-contacts", m.get("n_recontacts")), ("goal error", f"{1e3 * m['goal_error']:.2f} mm"
                                                 if isinstance(m.get("goal_error"), float) else None)) if v is not None)
    head = (f"<h1>{esc(plan.task.get('name', 'plan'))}: {esc(plan.status)} "
            f"({esc(plan.variant.get('oe', '?'))}/{esc(plan.variant.get('ss', '?'))})</h1>\n"
            + (f'<p id="reason">{esc(plan.reason)}</p>\n' if plan.reason else "")
            + (f'<p id="facts">{esc(facts)}</p>\n' if facts else ""))
    page = (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n<title>{esc(title)}</title>\n'
            "<style>body{font-family:system-ui,sans-serif;margin:1em 2em} h1{font-size:1.3em} "
            "p{max-width:70em;color:#444}</style>\n"
            f"<script>{plotly_js()}</script>\n</head>\n<body>\n{head}<div id=\"plan\"></div>\n"
            f'<script type="application/json" id="figure">{fig}</script>\n'
            "<script>\n(function () {\n  var fig = JSON.parse(document.getElementById('figure').textContent);\n"
            "  Plotly.newPlot('plan', fig.data, fig.layout, {responsive: true}).then(function (gd) {\n"
            "    return Plotly.addFrames(gd, fig.frames);\n  }).then(function () { window.ttReady = true; });\n"
            "})();\n</script>\n</body>\n</html>\n")
    return write_text(out, page)
