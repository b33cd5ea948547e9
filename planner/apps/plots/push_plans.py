"""Push plans side by side (like the paper's Fig. 10): universal path, condensed object path coloured
by the pushing face, tool outlines where each push starts, obstacles (with their safety margin)
and the target."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, Obstacle
from tooltransfer.tools.pose import rotation

MM = 1e3  # the figures draw lengths in mm (the plans are in m)


def plot_push_plans(
    plans: Mapping[str, PushPlan],
    tool: Tool,
    out: str | Path,
    *,
    radius: float,
    obstacles: Sequence[Obstacle] = (),
    margin: float = 0.0,
    target: np.ndarray | None = None,
    title: str = "",
) -> Path:
    """Write one panel per plan to ``out`` (PNG or PDF); returns the path. ``radius`` [m]: the object's."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = dict(zip(tool.face_names, plt.rcParams["axes.prop_cycle"].by_key()["color"][1:], strict=False))
    fig, axes = plt.subplots(1, len(plans), figsize=(5.2 * len(plans), 5.2), squeeze=False)
    outline = np.asarray(tool.outline.exterior.coords)
    for ax, (name, plan) in zip(axes[0], plans.items(), strict=True):
        ax.plot(*(MM * plan.universal).T, "k--", lw=1, label="generalized universal path")
        if plan.status != "solved":
            ax.text(0.5, 0.5, f"infeasible:\n{plan.reason}", transform=ax.transAxes, ha="center", wrap=True)
        for p in plan.pushes:
            seg = MM * plan.object_xy[p.samples]
            ax.plot(*seg.T, color=colours[p.face], lw=2.2, label=f"push: {p.face}")
            x, y, yaw = p.tool_pose[0]
            ring = MM * (outline @ rotation(yaw).T + [x, y])
            ax.fill(*ring.T, color=colours[p.face], alpha=0.35, lw=0.6)
            c = seg[0]
            ax.add_patch(plt.Circle(tuple(c), MM * radius, fill=False, color=colours[p.face], lw=0.7))
            ax.plot(*seg[0], "k.", ms=5)
        for o in obstacles:
            shape = o.polygon() if isinstance(o, Disc) else o
            ax.fill(*(MM * np.asarray(shape.exterior.coords)).T, color="tab:red", alpha=0.4)
            if margin > 0:
                ax.plot(*(MM * np.asarray(shape.buffer(radius + margin).exterior.coords)).T, ":", color="tab:red",
                        lw=0.8)
        if target is not None:
            ax.plot(*(MM * np.asarray(target)), "k*", ms=10, label="target")
        m = plan.metrics
        if plan.status == "solved":
            ax.set_title(f"{name}: {len(plan.pushes)} pushes, goal error {1e3 * m['goal_error']:.2f} mm,\n"
                         f"max cone violation {m['cone_violation_max']:.1e} rad, "
                         f"reach violation {1e3 * m['reach_violation_max']:.2f} mm", fontsize=9)
        handles, labels = ax.get_legend_handles_labels()
        uniq = dict(zip(labels, handles, strict=True))
        ax.legend(uniq.values(), uniq.keys(), fontsize=7, loc="best")
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
    if title:
        fig.suptitle(title)
    return save_figure(fig, out)
