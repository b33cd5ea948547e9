"""Demonstrations with their segmentation (like the paper's Figs. 4b and 8a): object tracks, tool
tracks, pushes coloured by face, corners (fixed points) marked, the scene's obstacle and target."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from planner.segmentation import Segmentation
from problems.dataset import Dataset
from tools.model import Tool


def plot_demonstrations(ds: Dataset, segs: Sequence[Segmentation], tool: Tool, out: str | Path) -> Path:
    """Write the figure to ``out``; returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = dict(zip(tool.face_names, ("tab:blue", "tab:orange", "tab:green", "tab:purple"), strict=False))
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(12, 6))
    for d, s in zip(ds.demonstrations, segs, strict=True):
        ax0.plot(*d.object_xy.T, ".", color="0.6", ms=1.5)
        ax1.plot(*d.tool_pose[:, :2].T, "-", color="0.7", lw=0.5)
        for p in s.pushes:
            ax0.plot(*s.object_at_tool[p.samples].T, "-", color=colours[p.face], lw=1.5)
            ax1.plot(*d.tool_pose[p.samples, :2].T, "-", color=colours[p.face], lw=1.2)
        if len(s.fixed_points):
            ax0.plot(*s.fixed_points.T, "k^", ms=5)
    scene = ds.meta.scene or {}
    for ax in (ax0, ax1):
        if "obstacle" in scene:
            o = scene["obstacle"]
            ax.add_patch(plt.Circle(tuple(o["centre"]), o["radius"], color="tab:red", alpha=0.5))
        if "corners" in scene:
            c = np.asarray(scene["corners"])
            h = scene.get("target_half", 0.0)
            ax.add_patch(plt.Rectangle(tuple(c[-1] - h), 2 * h, 2 * h, fill=False, color="k", ls="--"))
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    for name, col in colours.items():
        ax0.plot([], [], color=col, label=f"push: {name}")
    ax0.plot([], [], "k^", label="fixed points (corners)")
    ax0.legend(fontsize=8)
    ax0.set_title("object tracks (camera, 30 Hz) and segmented pushes", fontsize=9)
    ax1.set_title("tool tracks (encoders); pushing stretches coloured by face", fontsize=9)
    fig.tight_layout()
    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
