"""The heading drift on the simulated Omni, drawn: ``python -m tooltransfer.planner.apps.plots.heading_drift OUT.png``.

The Omni's last joints are fixed, so the tool's heading follows the waist angle q1 (docs/design.md
section 7): it cannot be held while the tool moves sideways. Tool 1's left face starts 5 mm right
of the puck at (40, 160) mm and sweeps 80 mm to the left. Panels:

(a) top view: the tool's outline and the puck every 0.5 s (light to dark), the commanded tool path
    (dashed), the puck's track, and where an ideal push straight to the left would take it;
(b) the tool's heading against its x: measured in MuJoCo and predicted by q1 (the IK);
(c) the puck's sideways drift (y) over time, with the tool-puck contact shaded: the face's normal
    leans forward, the round puck is pushed along it, rolls up the face and round the head, and
    is left behind.

Prints the measured figures (the heading's turn over the sweep, the puck's drift).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.tools import OBJECT_RADIUS, load_tool
from tooltransfer.tools.pose import Pose2D
from tooltransfer.tools.sim import Rates, SimPlatform
from tooltransfer.tools.sim.scenarios import sideways_sweep


def main(argv: list[str] | None = None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="figure file to write (.png, .pdf, .svg)")
    args = parser.parse_args(argv)

    sim = SimPlatform(load_tool("finger"))
    push = sideways_sweep(sim, (0.04, 0.16), sweep=0.08, gap=0.005, duration=5.0,
                          rates=Rates(object_hz=1000.0, tool_hz=1000.0))
    ex = push.execution
    mm = 1e3

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8), gridspec_kw={"width_ratios": [1.4, 1, 1]})
    ax = axes[0]
    times = np.arange(0.0, ex.t_tool[-1], 0.5)
    for k, tk in enumerate(times):
        shade = plt.cm.viridis(k / max(1, len(times) - 1))
        i = int(np.searchsorted(ex.t_tool, tk))
        outline = Pose2D(*ex.tool_pose[i]).place(sim.tool.outline)
        x, y = outline.exterior.xy
        ax.fill(mm * np.asarray(x), mm * np.asarray(y), color=shade, alpha=0.35, lw=0.8, ec=shade)
        j = int(np.searchsorted(ex.t_object, tk))
        ax.add_patch(plt.Circle(mm * ex.object_xy[j], mm * OBJECT_RADIUS, fill=False, color=shade, lw=1.2))
    ax.plot(mm * push.tool_path[:, 0], mm * push.tool_path[:, 1], "k--", lw=1, label="commanded tool path")
    ax.plot(mm * ex.object_xy[:, 0], mm * ex.object_xy[:, 1], "r-", lw=1.5, label="puck centre (MuJoCo)")
    start = push.object_start
    ideal = np.array([start, start + np.array([push.object_motion[0], 0.0])])
    ax.plot(mm * ideal[:, 0], mm * ideal[:, 1], "b:", lw=1.5, label="ideal push straight left")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title("(a) tool 1 sweeping left: outline and puck every 0.5 s")
    ax.legend(loc="lower left", fontsize=8)

    ax = axes[1]
    predicted = sim.platform.heading(ex.joints_ref[:, 0])
    ax.plot(mm * ex.tool_pose[:, 0], np.degrees(ex.tool_pose[:, 2]), "k-", label="measured (MuJoCo)")
    ax.plot(mm * ex.tool_pose[:, 0], np.degrees(predicted), "c--", label="q1 of the IK reference")
    ax.invert_xaxis()
    ax.set_xlabel("tool x [mm] (moving left)")
    ax.set_ylabel("tool heading [deg]")
    ax.set_title(f"(b) heading turns {np.degrees(push.heading_change):.1f} deg over the sweep")
    ax.legend(fontsize=8)

    ax = axes[2]
    ax.plot(ex.t_object, mm * (ex.object_xy[:, 1] - start[1]), "r-", label="puck y drift")
    ax.plot(ex.t_object, mm * (ex.object_xy[:, 0] - start[0]), "r:", label="puck x (pushed left)")
    for e in ex.contacts:
        ax.axvspan(e.t_start, e.t_end, color="0.85", label="tool-puck contact")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("[mm]")
    ax.set_title("(c) pushed left, the puck drifts forward")
    ax.legend(fontsize=8)

    path = save_figure(fig, args.out, dpi=120)
    dx, dy = mm * push.object_motion
    print(f"heading change {np.degrees(push.heading_change):.1f} deg over an {mm * 0.08:.0f} mm sweep; "
          f"puck moved {dx:.1f} mm in x and drifted {dy:.1f} mm in y; contact "
          f"{ex.contacts[0].t_start:.2f}-{ex.contacts[-1].t_end:.2f} s; max penetration "
          f"{1e6 * ex.max_penetration:.0f} um; figure: {path}")
    return path


if __name__ == "__main__":
    main()
