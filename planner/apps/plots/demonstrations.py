"""Demonstrations with their segmentation, like the paper's Figs. 4b and 8a.

Three panels: (a) the object tracks (camera samples, grey) with each push's stretch of the
smoothed track coloured by its face, the corners (fixed points) marked, the start, the obstacles
and the target square; (b) the tool tracks (encoders), grey during switches and coloured by face
while pushing, with the contact points of each switch; (c) a time line per demonstration: the
segmented pushes as coloured bars and, for generated data, the operator's ground truth below them.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.planner.learning.segmentation import Segmentation
from tooltransfer.problems.dataset import Dataset
from tooltransfer.tools.model import Tool

if TYPE_CHECKING:
    from matplotlib.axes import Axes

FACE_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown")
MM = 1e3  # the figures draw lengths in mm (the data are in m)


def _scene_patches(ax: Axes, scene: dict) -> None:
    import matplotlib.pyplot as plt

    obstacles = scene.get("obstacles") or ([scene["obstacle"]] if "obstacle" in scene else [])
    for o in obstacles:
        ax.add_patch(plt.Circle(tuple(MM * np.asarray(o["centre"])), MM * o["radius"], color="tab:red", alpha=0.45,
                                lw=0))
    target = scene.get("target") or (scene["corners"][-1] if "corners" in scene else None)
    if target is not None:
        h = MM * float(scene.get("target_half", 0.0))
        x, y = MM * np.asarray(target, dtype=float)
        ax.add_patch(plt.Rectangle((x - h, y - h), 2 * h, 2 * h, fill=False, color="k", ls="--"))
    start = scene.get("start") or (scene["corners"][0] if "corners" in scene else None)
    if start is not None:
        ax.plot(*(MM * np.asarray(start, dtype=float)), "ko", mfc="none", ms=7)


def plot_demonstrations(ds: Dataset, segs: Sequence[Segmentation], tool: Tool, out: str | Path) -> Path:
    """Write the figure of the dataset ``ds`` segmented as ``segs`` (one per demonstration) to
    ``out`` (PNG or any matplotlib format); returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = dict(zip(tool.face_names, FACE_COLOURS, strict=False))
    fig = plt.figure(figsize=(15, 6.2))
    grid = fig.add_gridspec(1, 3, width_ratios=[1.0, 1.0, 1.1])
    ax0, ax1, ax2 = (fig.add_subplot(grid[0, i]) for i in range(3))
    for d, s in zip(ds.demonstrations, segs, strict=True):
        ax0.plot(*(MM * d.object_xy).T, ".", color="0.75", ms=1.2, zorder=1)
        ax1.plot(*(MM * d.tool_pose[:, :2]).T, "-", color="0.75", lw=0.5, zorder=1)
        for p in s.pushes:
            ax0.plot(*(MM * s.object_at_tool[p.samples]).T, "-", color=colours[p.face], lw=1.3, zorder=2)
            ax1.plot(*(MM * d.tool_pose[p.samples, :2]).T, "-", color=colours[p.face], lw=1.0, zorder=2)
        for w, c in zip(s.switches, s.fixed_points, strict=False):
            for q in (w.object_point_from, w.object_point_to):
                ax0.plot(*(MM * np.vstack([c, q])).T, "k-", lw=0.5, zorder=3)
        if len(s.fixed_points):
            ax0.plot(*(MM * np.asarray(s.fixed_points)).T, "k^", ms=6, mfc="yellow", zorder=4)
    scene = ds.meta.scene or {}
    for ax in (ax0, ax1):
        _scene_patches(ax, scene)
        ax.set_aspect("equal")
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        ax.grid(alpha=0.3)
    for name, col in colours.items():
        ax0.plot([], [], color=col, label=f"push: {name} face")
    ax0.plot([], [], "k^", mfc="yellow", label="fixed points (corners)")
    ax0.plot([], [], "k-", lw=0.5, label="to the contact points of a switch")
    ax0.legend(fontsize=7, loc="lower left")
    ax0.set_title("(a) object tracks (camera) and segmented pushes", fontsize=9)
    ax1.set_title("(b) tool tracks (encoders): pushing by face, switching grey", fontsize=9)
    truth = ds.truth or {}
    for i, (d, s) in enumerate(zip(ds.demonstrations, segs, strict=True)):
        y = len(ds.demonstrations) - 1 - i
        for p in s.pushes:
            ax2.broken_barh([(p.t_start, p.t_end - p.t_start)], (y + 0.05, 0.5), color=colours[p.face])
        for p in truth.get(d.name, {}).get("pushes", []):
            ax2.broken_barh([(p["t_start"], p["t_end"] - p["t_start"])], (y - 0.35, 0.3),
                            color=colours.get(p["face"], "k"), alpha=0.45)
        for w in s.switches:
            ax2.plot([w.t_start, w.t_end], [y + 0.3, y + 0.3], "k-", lw=0.6)
    ax2.set_yticks(range(len(ds.demonstrations)), [d.name for d in reversed(ds.demonstrations)], fontsize=7)
    ax2.set_xlabel("t [s]")
    ax2.set_title("(c) pushes per demonstration: segmented (top)" + (", truth (bottom)" if truth else ""),
                  fontsize=9)
    return save_figure(fig, out, dpi=110)
