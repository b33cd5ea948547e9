"""Draw the tool library (faces, push cones, contact ranges) and the Omni's reachable table region.

Written by ``tooltransfer tools --out out/tools.png``.

Top: every library tool in its tool frame [mm] with its convex pieces (thin lines), faces
(thick, contact range in orange), and push cones (yellow wedges of half-angle theta_b about the
push direction). Bottom: the reachable region of the default Omni with tool 1 in the world frame
[mm], the Omni's published 160 x 70 mm footprint, and tool poses in contact with the object whose
heading is the one the Omni imposes at that place.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Circle, Polygon, Wedge

from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.tools import OBJECT_RADIUS, Tool, contact_on_platform, load_library, tool_polygon
from tooltransfer.tools.omni import OmniPlatform, reach_sector, reachable_polygon

MM = 1000.0


def draw_tool(ax: plt.Axes, tool: Tool) -> None:
    """One tool in its frame [mm]: outline, convex pieces, faces, cones, tool centre point."""
    ring = np.asarray(tool.outline.exterior.coords) * MM
    ax.add_patch(Polygon(ring, closed=True, fc="#9ecae1", ec="#08519c", lw=1.2))
    for piece in tool.convex_pieces:
        ax.plot(*(np.asarray(piece.exterior.coords) * MM).T, color="#08519c", lw=0.4, ls=":")
    cone_r = 12.0
    for f in tool.faces:
        ax.plot(*np.stack([f.start, f.end]).T * MM, color="#d62728", lw=3.0, solid_capstyle="butt")
        a, b = f.contact_segment()
        ax.plot(*np.stack([a, b]).T * MM, color="#ff7f0e", lw=5.0, alpha=0.8, solid_capstyle="butt")
        mid = 0.5 * (a + b) * MM
        centre = mid + 2.0 * f.normal
        lo, hi = np.degrees(f.push_angle - f.theta_b), np.degrees(f.push_angle + f.theta_b)
        ax.add_patch(Wedge(centre, cone_r, lo, hi, fc="#ffd92f", ec="#b8860b", alpha=0.7, lw=0.8))
        d = f.push_direction
        ax.annotate("", centre + cone_r * d, centre, arrowprops={"arrowstyle": "->", "lw": 1.2})
        ax.text(*(centre + (cone_r + 4) * d), f.name, fontsize=7, ha="center", va="center")
    ax.plot(0, 0, "k+", ms=8)
    ax.set_title(f"{tool.name}  (a_t = {tool.a_t * MM:g} mm)", fontsize=9)
    ax.set_aspect("equal")
    ax.set_xlim(-40, 60)
    ax.set_ylim(-38, 48)
    ax.tick_params(labelsize=7)


def draw_reach(ax: plt.Axes, tools: dict[str, Tool]) -> None:
    """Reachable region of the default platform with tool 1 and a few contact poses [mm]."""
    platform = OmniPlatform(a_t=tools["finger"].a_t)
    poly = reachable_polygon(platform)
    sec = reach_sector(platform)
    ax.add_patch(
        Polygon(
            np.asarray(poly.exterior.coords) * MM,
            fc="#e5f5e0",
            ec="#31a354",
            lw=1.5,
            label=f"reachable (area {poly.area * 1e4:.0f} cm$^2$)",
        )
    )
    ax.add_patch(
        Polygon(
            [[-80, 130], [80, 130], [80, 200], [-80, 200]],
            fill=False,
            ec="gray",
            ls="--",
            lw=1.0,
            label="published 160 x 70 mm footprint",
        )
    )
    ax.plot(0, 0, "ks", ms=6, label="Omni joint-1 axis (world origin)")
    for q1 in sec.q1_range:
        a = sec.point(q1, np.array([0.0, sec.u_range[0]])) * MM
        ax.plot(*a.T, color="gray", lw=0.6, ls=":")
    cases = [
        ("finger", "upper", (-0.06, 0.175), np.pi / 2),
        ("finger", "left", (0.075, 0.115), np.pi),
        ("slope", "inclined", (0.0, 0.19), 0.75 * np.pi),
        ("t_shape", "top", (0.115, 0.165), np.radians(60)),
        ("trapezoid", "left", (-0.13, 0.12), np.radians(-145)),
    ]
    colours = ["#3182bd", "#6baed6", "#e6550d", "#756bb1", "#31a354"]
    for (name, face, centre, direction), colour in zip(cases, colours, strict=True):
        tool = tools[name]
        res = contact_on_platform(tool, face, centre, direction, platform.with_a_t(tool.a_t))
        ax.add_patch(Circle(np.multiply(centre, MM), OBJECT_RADIUS * MM, fc="#a50f15", alpha=0.6))
        if res.contact is None:
            continue
        placed = tool_polygon(tool, res.contact.pose)
        cone = "in cone" if res.in_cone else "outside cone"
        ax.add_patch(
            Polygon(
                np.asarray(placed.exterior.coords) * MM,
                fc=colour,
                alpha=0.8,
                ec="k",
                lw=0.6,
                label=f"{name}/{face} push {np.degrees(direction):.0f} deg ({cone})",
            )
        )
        p = np.multiply(centre, MM)
        ax.annotate(
            "",
            p + 25 * np.array([np.cos(direction), np.sin(direction)]),
            p,
            arrowprops={"arrowstyle": "->", "lw": 1.5},
        )
    ax.set_aspect("equal")
    ax.set_xlim(-200, 200)
    ax.set_ylim(-15, 235)
    ax.set_xlabel("x [mm] (operator's right)")
    ax.set_ylabel("y [mm] (forward)")
    ax.set_title(
        "Omni reach on the table (default platform, tool 1) and contact poses", fontsize=10
    )
    ax.legend(fontsize=7, loc="lower left")
    ax.grid(alpha=0.3)


def plot_tool_library(out: str | Path) -> Path:
    """Write the figure (PNG) to ``out``; returns the path."""
    tools = load_library()
    cols, rows = 4, -(-len(tools) // 4)
    fig = plt.figure(figsize=(14, 4 * rows + 6))
    grid = fig.add_gridspec(rows + 1, cols, height_ratios=[1] * rows + [1.6])
    for k, name in enumerate(sorted(tools)):
        draw_tool(fig.add_subplot(grid[k // cols, k % cols]), tools[name])
    draw_reach(fig.add_subplot(grid[rows, :]), tools)
    return save_figure(fig, out, dpi=110)
