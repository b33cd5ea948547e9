"""The figure of a verdict's certificate: where any face can hold the puck (the push space), the
backward-reachable set of the target (``backward_reachable``) or the side of the start of the
quantity no push decreases (``polar_invariant``), the obstacles, the start and the target, seen from
above (lengths in mm)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import shapely

from tooltransfer.planner.apps.plots.save import save_figure


def _fill(ax: Any, geom: shapely.Geometry, **style: Any) -> None:
    """Fill every polygon of ``geom`` [m] on ``ax`` in mm (holes drawn white)."""
    first = True
    for poly in shapely.get_parts(geom):
        if shapely.get_type_id(poly) != 3:
            continue
        xy = 1e3 * np.asarray(poly.exterior.coords)
        ax.fill(xy[:, 0], xy[:, 1], label=style.pop("label", None) if first else None, **style)
        first = False
        for ring in poly.interiors:
            h = 1e3 * np.asarray(ring.coords)
            ax.fill(h[:, 0], h[:, 1], color="white")


def certificate_figure(evidence: dict[str, Any], obstacles: list[dict[str, Any]], out: str | Path) -> Path:
    """Draw the certificate of a plan's ``evidence`` (:attr:`tooltransfer.planner.planning.plan.Plan.evidence`
    of an ``infeasible`` verdict) with the plan's ``obstacles`` (plan-file form) to ``out`` (a PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cert = evidence["certificate"]
    fig, ax = plt.subplots(figsize=(6.4, 5.2))
    _fill(ax, shapely.from_wkt(cert["space_wkt"]), color="#dfe8f2", label="push space (any face can hold the puck)")
    if cert.get("region_wkt"):
        # the invariant's side of the start, or the faces' sets grown from the start: not the target's set
        forward = cert["kind"] in ("polar_invariant", "switch_separated", "forward_backward")
        label = ("positions a plan from the start could reach" if forward else "positions that could reach the target")
        if cert["kind"] == "forward_backward":
            label += ",\nof those that could still reach the target"
        _fill(ax, shapely.from_wkt(cert["region_wkt"]), color="#a9d18e" if forward else "#f4b183", alpha=0.8,
              label=label)
    for i, o in enumerate(obstacles):
        shape = (shapely.Point(o["centre"]).buffer(o["radius"]) if o["kind"] == "disc"
                 else shapely.Polygon(o["vertices"]))
        _fill(ax, shape, color="#555555", label="obstacle" if i == 0 else None)
    s, t = 1e3 * np.asarray(cert["start"]), 1e3 * np.asarray(cert["target"])
    ax.plot(*s, "o", color="#1f77b4", label="start")
    ax.plot(*t, "*", color="#d62728", markersize=12, label="target")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"certified infeasible: {cert['kind']}", fontsize=10)
    ax.legend(fontsize=7, loc="best")
    return save_figure(fig, out)
