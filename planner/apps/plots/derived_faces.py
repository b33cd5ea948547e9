"""Draw an outline with the contacts derived from it (``tooltransfer tools derive OUTLINE --plot FIG``).

Tool frame [mm]: the outline (blue), each derived face (``edge_<i>``: the whole edge thin red, its usable
part thick orange) with its outward normal (arrow) and friction cone (yellow wedge of half-angle
``atan(mu)``), edges the object touches but the planner does not use (grey), convex vertices used as
point pushers (black dots with a grey wedge of their contact normals), the object's disc at the
middle of each face's usable part (dashed) and the tool centre point (+).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Circle, Polygon, Wedge

from tooltransfer.planner.apps.plots.save import save_figure
from tooltransfer.tools.derive import Derivation

MM = 1000.0


def draw_derivation(ax: plt.Axes, d: Derivation, title: str = "") -> None:
    """``d``'s outline and contacts on ``ax`` (tool frame, mm)."""
    ring = np.asarray(d.outline.exterior.coords) * MM
    ax.add_patch(Polygon(ring, closed=True, fc="#9ecae1", ec="#08519c", lw=1.2))
    planned = {f.name for f in d.faces}
    cone_r = 10.0
    for e in d.edges:
        a, b = e.start + e.contact_range[0] * (e.end - e.start), e.start + e.contact_range[1] * (e.end - e.start)
        if e.name not in planned:
            ax.plot(*np.stack([a, b]).T * MM, color="0.5", lw=4.0, alpha=0.7, solid_capstyle="butt")
            continue
        ax.plot(*np.stack([e.start, e.end]).T * MM, color="#d62728", lw=2.0, solid_capstyle="butt")
        ax.plot(*np.stack([a, b]).T * MM, color="#ff7f0e", lw=5.0, alpha=0.85, solid_capstyle="butt")
        mid = 0.5 * (a + b)
        ax.add_patch(Circle(tuple((mid + d.radius * e.normal) * MM), d.radius * MM, fill=False, ec="#a50f15",
                            ls="--", lw=0.5, alpha=0.5))
        base = mid * MM + 1.5 * e.normal
        ang = np.degrees(e.normal_angle)
        half = np.degrees(e.friction_half)
        ax.add_patch(Wedge(tuple(base), cone_r, ang - half, ang + half, fc="#ffd92f", ec="#b8860b", alpha=0.7, lw=0.8))
        ax.annotate("", tuple(base + cone_r * e.normal), tuple(base), arrowprops={"arrowstyle": "->", "lw": 1.2})
        ax.text(*(base + (cone_r + 5) * e.normal), e.name, fontsize=7, ha="center", va="center")
    for v in d.vertices:
        p = v.point * MM
        ax.plot(*p, "k.", ms=5)
        lo, hi = np.degrees(v.normals)
        if hi > lo:
            ax.add_patch(Wedge(tuple(p), 4.0, lo, hi, fc="0.6", alpha=0.5, lw=0))
    ax.plot(0, 0, "k+", ms=8)
    ax.set_title(title or f"derived contacts (object radius {d.radius * MM:g} mm, mu {d.friction:g})", fontsize=9)
    ax.set_aspect("equal")
    lo, hi = ring.min(axis=0) - 25, ring.max(axis=0) + 25
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.tick_params(labelsize=7)


def plot_derivation(d: Derivation, out: str | Path, title: str = "") -> Path:
    """Write the figure of ``d`` (PNG, or the suffix's format) to ``out``; returns the path."""
    fig, ax = plt.subplots(figsize=(6, 6))
    draw_derivation(ax, d, title)
    return save_figure(fig, out, dpi=110)
