"""The safety margin and the tail effect around an obstacle (like the paper's Fig. 14).

Left: the outer map (7) applied to the universal path for several margins delta: the path is
pushed out of the obstacle's disc grown by the object's radius and delta, and points far from it
move less and less (the "tail"). Right: the condensed object paths of both OE variants with one
margin, with the clearance each keeps.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.planner.planning.oe.mapping_variant import avoid_obstacles
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.problems.task import MAPPING_K
from tooltransfer.tools.objects import Disc

MM = 1e3  # the figures draw lengths in mm (the paths are in m)


def plot_safety_margin(
    universal: np.ndarray,
    obstacle: Disc,
    plans: Mapping[str, PushPlan],
    out: str | Path,
    *,
    radius: float,
    margins: Sequence[float] = (0.0, 0.005, 0.01),
    k: float = MAPPING_K,
) -> Path:
    """Write the figure to ``out``; ``universal`` (T, 2) [m] is the generalized universal path of an
    object of ``radius`` [m]."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 5.2))
    for ax in (ax0, ax1):
        ax.add_patch(plt.Circle(tuple(MM * np.asarray(obstacle.centre)), MM * obstacle.radius, color="tab:red",
                                alpha=0.4))
        ax.plot(*(MM * universal).T, "k--", lw=1, label="universal path")
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
    for delta in margins:
        mapped = avoid_obstacles(universal, [obstacle], k, delta, radius)
        line = ax0.plot(*(MM * mapped).T, lw=1.4, label=f"outer (7), delta = {1e3 * delta:.0f} mm")[0]
        ax0.add_patch(plt.Circle(tuple(MM * np.asarray(obstacle.centre)), MM * (obstacle.radius + radius + delta),
                                 fill=False, ls=":", color=line.get_color(), lw=0.8))
    shift = np.linalg.norm(avoid_obstacles(universal, [obstacle], k, margins[-1], radius) - universal, axis=1)
    far = np.linalg.norm(universal - obstacle.centre, axis=1) > 3 * (obstacle.radius + radius)
    ax0.set_title(f"tail effect: points beyond 3 r_b still move up to {1e3 * shift[far].max(initial=0):.1f} mm",
                  fontsize=9)
    ax0.legend(fontsize=7)
    for name, plan in plans.items():
        if plan.status != "solved":
            continue
        clear = plan.metrics.get("obstacle_clearance_min", float("nan"))
        ax1.plot(*(MM * plan.object_xy).T, lw=1.6, label=f"{name}: clearance {1e3 * clear:.1f} mm")
    ax1.set_title("condensed object paths (clearance = object edge to obstacle edge)", fontsize=9)
    ax1.legend(fontsize=7)
    return save_figure(fig, out)
