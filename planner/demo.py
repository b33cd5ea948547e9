"""The main job until the planner exists: fit a DMP to an L-shaped push, with and without cone
constraints, and write a figure and a table of fit error and solve time."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from dmp.qp import FitProblem, TrackPath, solve_fit
from problems.fit_cases import l_push_case


def run_demo(out: Path) -> str:
    """Run the demo, write ``out/demo.png`` and ``out/demo.txt``; return the table text."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    case = l_push_case(30, 200)
    free = FitProblem(case.problem.dmp, case.t, case.reference[0], case.reference[-1], [TrackPath(case.reference)])
    rows = []
    results = {}
    for name, prob in (("unconstrained", free), ("cone+workspace+obstacle", case.problem)):
        start = time.perf_counter()
        r = solve_fit(prob)
        wall = time.perf_counter() - start
        ref = np.interp(r.rollout.t, case.t, case.reference[:, 0]), np.interp(r.rollout.t, case.t, case.reference[:, 1])
        rmse = float(np.sqrt(np.mean((r.rollout.x[:, 0] - ref[0]) ** 2 + (r.rollout.x[:, 1] - ref[1]) ** 2)))
        results[name] = r
        rows.append(f"{name:<26} {r.status:<9} {1e3 * rmse:9.3f} {1e3 * wall:10.1f} {r.max_violation:12.2e}")
    table = "\n".join([f"{'fit':<26} {'status':<9} {'RMSE[mm]':>9} {'time[ms]':>10} {'max viol':>12}", *rows])
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.plot(case.reference[:, 0], case.reference[:, 1], "k--", label="demonstrated L push")
    for name, r in results.items():
        ax.plot(r.rollout.x[:, 0], r.rollout.x[:, 1], label=name)
    from problems.fit_cases import HEXAGON

    hexa = np.vstack([HEXAGON, HEXAGON[:1]])
    ax.plot(hexa[:, 0], hexa[:, 1], "g-", lw=0.8, label="workspace")
    ax.add_patch(plt.Circle((0.006, 0.045), 0.012, color="r", alpha=0.3, label="obstacle"))
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize=8)
    fig.savefig(out / "demo.png", dpi=120)
    (out / "demo.txt").write_text(table + "\n")
    return table
