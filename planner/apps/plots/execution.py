"""A plan and its execution (like the paper's Fig. 12): (a) the planned object path coloured by
phase with the tool outline at the start of every push and along the switches; (b) planned versus
executed object and tool paths on the simulated platform, with the final object error; and an
animated GIF of the execution (tool outline and puck over time)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from tooltransfer.atomic import atomic_path
from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.tools.sim.execution import Execution

#: The tool reference point's colour in each phase of a plan (four phases, four colours).
PHASE_COLOURS = {"approach": "0.55", "push": "tab:blue", "switch": "tab:orange", "retreat": "tab:purple"}


def _outline(plan: Plan) -> NDArray[np.float64]:
    return np.asarray(plan.tool["outline"] + plan.tool["outline"][:1], dtype=float)


def _placed(outline: NDArray[np.float64], pose: NDArray[np.float64]) -> NDArray[np.float64]:
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return outline @ np.array([[c, s], [-s, c]]) + pose[:2]


def _scene(ax, plan: Plan) -> None:  # type: ignore[no-untyped-def]
    """The table's content on ``ax`` [mm], each kind once in the legend: obstacles (filled) with
    their safety margin (dotted), the puck at its start, the target (the puck's square at the goal)."""
    import matplotlib.pyplot as plt

    margin = float(plan.task.get("safety_margin", 0.0))
    for i, o in enumerate(plan.obstacles):
        first = {"label": "obstacle"} if i == 0 else {}
        if o["kind"] == "disc":
            c = 1e3 * np.asarray(o["centre"])
            ax.add_patch(plt.Circle(tuple(c), 1e3 * o["radius"], color="tab:red", alpha=0.5, **first))
            more = {"label": "safety margin"} if i == 0 and margin > 0 else {}
            ax.add_patch(plt.Circle(tuple(c), 1e3 * (o["radius"] + margin), color="tab:red", fill=False, ls=":",
                                    **more))
        else:
            ax.add_patch(plt.Polygon(1e3 * np.asarray(o["vertices"]), color="tab:red", alpha=0.5, **first))
    r = 1e3 * plan.object["radius"]
    ax.add_patch(plt.Circle(tuple(1e3 * np.asarray(plan.object["start"])), r, fill=False, color="k", lw=0.8,
                            label="puck (start)"))
    ax.add_patch(plt.Rectangle(tuple(1e3 * np.asarray(plan.object["goal"]) - r), 2 * r, 2 * r, fill=False,
                               color="tab:green", lw=1.2, label="target"))
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")


def _face_label(ax, name: str, outline: NDArray[np.float64], puck: NDArray[np.float64]) -> None:  # type: ignore[no-untyped-def]
    """Write a face's name beside the placed tool ``outline`` (V, 2) [mm]: just outside its vertex
    farthest from the ``puck`` (2,) [mm] (the tool's free end, clear of the contact and of the
    outline), on a white ground so the other outlines under it stay apart from the text."""
    centre = outline[:-1].mean(axis=0)
    tip = outline[int(np.argmax(np.linalg.norm(outline[:-1] - puck, axis=1)))]
    out = tip - centre
    out = out / np.linalg.norm(out) if np.linalg.norm(out) > 1e-9 else np.array([1.0, 0.0])
    ax.annotate(name, tuple(tip + 1.5 * out), fontsize=7, color="tab:blue", ha="left" if out[0] >= 0 else "right",
                va="bottom" if out[1] >= 0 else "top",
                bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.85})


def _legend_below(ax) -> None:  # type: ignore[no-untyped-def]
    """The panel's legend under its x label, in three columns: never over the paths."""
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=3, frameon=False, markerscale=4)


def draw_plan(ax, plan: Plan, title: str) -> None:  # type: ignore[no-untyped-def]
    """Draw a plan on ``ax``: the scene, the tool reference point by phase, the object path, the tool
    outline at the start of every push and at four instants of every switch. A plan without samples
    (infeasible) shows why in the panel; a violated one is drawn with what it breaks."""
    import textwrap

    _scene(ax, plan)
    if plan.status != "solved" and plan.t.size < 2:
        ax.set_title(f"{title}\n{plan.status}", fontsize=9)
        why = textwrap.fill(plan.reason, 60, max_lines=8, placeholder=" ...")
        ax.text(0.5, 0.03, why, transform=ax.transAxes, ha="center", va="bottom", fontsize=7, color="tab:red",
                wrap=False)
        return
    if plan.status != "solved":
        title = f"{title}\n{plan.status}: {plan.reason.removeprefix('hard checks violated: ')[:90]}"
    outline = _outline(plan)
    phase = np.asarray(plan.phase)
    for name, colour in PHASE_COLOURS.items():
        m = phase == name
        if m.any():
            ax.plot(*(1e3 * plan.tool_pose[m, :2]).T, ".", ms=1.5, color=colour, label=f"tool ({name})")
    ax.plot(*(1e3 * plan.object_xy).T, "k-", lw=1.6, label="object")
    for p in plan.pushes:
        k = int(np.searchsorted(plan.t, p.t_start))
        placed = 1e3 * _placed(outline, plan.tool_pose[k])
        ax.plot(*placed.T, color="tab:blue", lw=1)
        _face_label(ax, p.faces[0], placed, 1e3 * plan.object_xy[k])
    for s in plan.switches:
        for k in np.linspace(np.searchsorted(plan.t, s.t_start), np.searchsorted(plan.t, s.t_end) - 1, 4).astype(int):
            ax.plot(*(1e3 * _placed(outline, plan.tool_pose[k])).T, color="tab:orange", lw=0.6, alpha=0.8)
    ax.set_title(title, fontsize=9)
    _legend_below(ax)


def plot_plans(plans: Mapping[str, Plan], out: str | Path, dpi: int = 120) -> Path:
    """One panel per plan (e.g. every variant pair of a task), side by side on shared axes [mm]. Returns
    the written path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(plans)
    cols = min(n, 2) if n == 4 else n
    rows = int(np.ceil(n / cols))
    # one scale for every panel (shared axes, limits over all of them): the variants compare at a glance
    fig, axes = plt.subplots(rows, cols, figsize=(5.4 * cols, 5.4 * rows), squeeze=False, sharex=True, sharey=True)
    for ax, (name, plan) in zip(axes.ravel(), plans.items(), strict=False):
        m = plan.metrics
        extra = ""
        if plan.status == "solved":
            extra = (f"\n{m.get('n_pushes', 0):.0f} pushes, cone violation {m.get('cone_violation_max', np.nan):.2g} "
                     f"rad, switch penetration {1e3 * m.get('switch_penetration_max', np.nan):.2f} mm")
        draw_plan(ax, plan, f"{name}{extra}")
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    for ax in axes.ravel()[:n]:
        ax.label_outer()
    return save_figure(fig, out, dpi)


def plot_plan(plan: Plan, out: str | Path, executions: Mapping[str, Execution] | None = None,
              dpi: int = 120) -> Path:
    """Fig. 12: panel (a) the plan; then one panel per execution (e.g. ``{"open loop": ex}``) with
    the planned and executed object and tool paths, on shared axes [mm]. Returns the written path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    executions = dict(executions or {})
    n = 1 + len(executions)
    fig, axes = plt.subplots(1, n, figsize=(5.4 * n, 5.4), squeeze=False, sharex=True, sharey=True)
    v = plan.variant
    draw_plan(axes[0, 0], plan, f"(a) plan {plan.task.get('name', '')}: oe {v.get('oe')}, ss {v.get('ss')}")
    goal = np.asarray(plan.object["goal"])
    for i, (name, ex) in enumerate(executions.items()):
        ax = axes[0, i + 1]
        _scene(ax, plan)
        ax.plot(*(1e3 * plan.object_xy).T, "k--", lw=1.2, label="object, planned")
        ax.plot(*(1e3 * ex.object_xy).T, "k-", lw=1.2, label="object, executed")
        ax.plot(*(1e3 * plan.tool_pose[:, :2]).T, "--", color="tab:blue", lw=0.8, label="tool, planned")
        ax.plot(*(1e3 * ex.tool_pose[:, :2]).T, "-", color="tab:blue", lw=0.8, label="tool, executed")
        err = float(np.linalg.norm(ex.object_xy[-1] - goal))
        ax.set_title(f"({chr(98 + i)}) {name}: final object error {1e3 * err:.1f} mm", fontsize=9)
        _legend_below(ax)
    for ax in axes[0]:
        ax.label_outer()  # the panels share their axes [mm]
    return save_figure(fig, out, dpi)


def animate_execution(plan: Plan, ex: Execution, out: str | Path, *, fps: int = 10, speed: float = 4.0) -> Path:
    """An animated GIF of an execution: the tool outline and the puck at ``fps`` frames per second,
    ``speed`` times faster than real time, over the planned paths. Returns the written path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    fig, ax = plt.subplots(figsize=(5, 5))
    _scene(ax, plan)
    ax.plot(*(1e3 * plan.object_xy).T, "k--", lw=0.8)
    outline = _outline(plan)
    r = 1e3 * plan.object["radius"]
    times = np.arange(ex.t_tool[0], ex.t_tool[-1], speed / fps)
    pts = 1e3 * np.vstack([plan.tool_pose[:, :2], ex.tool_pose[:, :2], ex.object_xy])
    lo, hi = pts.min(axis=0) - 30, pts.max(axis=0) + 30
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    (tool_line,) = ax.plot([], [], color="tab:blue", lw=1.5)
    puck = plt.Circle((0.0, 0.0), r, color="tab:brown", alpha=0.7)
    ax.add_patch(puck)
    (trail,) = ax.plot([], [], "-", color="tab:brown", lw=1)
    label = ax.set_title("")

    def frame(i: int) -> tuple:
        t = times[i]
        k = min(int(np.searchsorted(ex.t_tool, t)), len(ex.t_tool) - 1)
        j = min(int(np.searchsorted(ex.t_object, t)), len(ex.t_object) - 1)
        tool_line.set_data(*(1e3 * _placed(outline, ex.tool_pose[k])).T)
        puck.center = tuple(1e3 * ex.object_xy[j])
        trail.set_data(*(1e3 * ex.object_xy[: j + 1]).T)
        label.set_text(f"t = {t:4.1f} s ({speed:g}x)")
        return tool_line, puck, trail, label

    anim = FuncAnimation(fig, frame, frames=len(times), blit=False)
    path = Path(out)
    try:
        with atomic_path(path) as tmp:
            anim.save(tmp, writer=PillowWriter(fps=fps), dpi=70)
    finally:
        plt.close(fig)
    return path
