"""The main job (``make demo``): the paper's transfer scenario end to end.

Learns the skills from the committed demonstrations (``problems/data/finger_demos``), compares the
OE variants (the paper's mapping and this project's QP search) on the transfer to tool 2
(``problems/paper/transfer_tool2.yaml``), executes the ``qp`` plan on the simulated platform, and
writes the figures and plan files to the output folder.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.plan import Plan
from problems.task import load_task

ROOT = Path(__file__).resolve().parents[1]
TRANSFER = ROOT / "problems" / "paper" / "transfer_tool2.yaml"


def compare(task_path: Path, out: Path) -> tuple[str, dict[str, Plan]]:
    """Solve a task with every OE variant; write the plans and a figure like Fig. 10; return the
    metrics table (text) and the plans."""
    from planner.plots.push_plans import plot_push_plans
    from planner.solve import solve
    from problems.task import task_obstacles, task_tool

    task = load_task(task_path)
    plans, push_plans = {}, {}
    for oe in ("mapping", "qp"):
        t = task.model_copy(update={"variants": task.variants.model_copy(update={"oe": oe})})
        plans[oe] = solve(t, task_path)
        plans[oe].write(out / f"plan_{task.name}_{oe}.json")
    keys = [("status", "", 1), ("n_pushes", "", 1), ("goal_error", "mm", 1e3), ("cone_violation_max", "rad", 1),
            ("reach_violation_max", "mm", 1e3), ("obstacle_clearance_min", "mm", 1e3),
            ("deviation_mean", "mm", 1e3), ("switch_clearance_min", "mm", 1e3), ("time_oe", "ms", 1e3)]
    lines = [f"{'metric':<24}" + "".join(f"{oe:>14}" for oe in plans)]
    for k, unit, scale in keys:
        row = f"{k + (f' [{unit}]' if unit else ''):<24}"
        for p in plans.values():
            v = p.status if k == "status" else p.metrics.get(k, float("nan"))
            row += f"{v:>14}" if isinstance(v, str) else f"{scale * v:>14.4g}"
        lines.append(row)
    from planner.oe.generalize import generalize
    from planner.oe.mapping_variant import condense_mapping
    from planner.oe.qp_variant import condense_qp
    from planner.skills import oe_skill_from_dataset
    from problems.task import resolve, task_platform

    tool = task_tool(task)
    platform, obstacles = task_platform(task, tool), task_obstacles(task)
    skill = oe_skill_from_dataset(resolve(task_path, task.skills.dataset), task.oe.k)
    tt, x, _ = generalize(skill.dmp, np.array(task.start), np.array(task.target))
    push_plans["mapping"] = condense_mapping(tt, x, tool, platform, np.array(task.target), obstacles)
    push_plans["qp"] = condense_qp(tt, x, tool, platform, np.array(task.target), obstacles)
    plot_push_plans(push_plans, tool, out / "fig10_condensed_paths.png", obstacles=obstacles,
                    margin=task.safety_margin, target=np.array(task.target), title=task.name)
    return "\n".join(lines), plans


def run_demo(out: Path) -> str:
    """Run the main job; returns the report text (also written to ``out/report.txt``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from planner.plots.demonstrations import plot_demonstrations
    from planner.plots.safety_margin import plot_safety_margin
    from planner.segmentation import segment
    from planner.simulate import simulate_plan
    from problems.dataset import load_dataset
    from problems.paper_cases import DEFAULT_DATASET, default_oe_skill, transfer_case
    from tools.library import load_tool

    out.mkdir(parents=True, exist_ok=True)
    ds = load_dataset(DEFAULT_DATASET)
    tool1 = load_tool(ds.meta.tool)
    plot_demonstrations(ds, [segment(d, tool1) for d in ds.demonstrations], tool1, out / "fig8a_demonstrations.png")
    skill = default_oe_skill()
    case = transfer_case()
    fig, ax = plt.subplots(figsize=(6, 5))
    for r in skill.recovered:
        ax.plot(*r.x.T, color="0.65", lw=0.8)
    ax.plot(*case.x.T, "r-", lw=2, label="universal OE skill")
    ax.set_aspect("equal")
    ax.set_title("recovered demonstrations (grey) and the learned skill (Fig. 8b)", fontsize=9)
    ax.legend(fontsize=8)
    fig.savefig(out / "fig8b_universal_skill.png", dpi=110)
    plt.close(fig)
    table, plans = compare(TRANSFER, out)
    from planner.oe.mapping_variant import condense_mapping
    from planner.oe.qp_variant import condense_qp

    args = (case.t, case.x, case.tool, case.platform, case.target, case.obstacles)
    plot_safety_margin(case.x, case.obstacles[0], {"mapping": condense_mapping(*args), "qp": condense_qp(*args)},
                       out / "fig14_safety_margin.png")
    report = ["transfer of tool 1's skills to tool 2 (problems/paper/transfer_tool2.yaml)", table]
    qp = plans["qp"]
    if qp.status == "solved":
        sim = simulate_plan(qp)
        report.append(
            f"simulated qp plan (open loop): final object error {1e3 * sim.final_error:.1f} mm, largest tool "
            f"deviation {1e3 * sim.tool_deviation:.1f} mm, {qp.t[-1]:.1f} s plan in {sim.wall_time:.2f} s"
        )
    text = "\n".join(report)
    (out / "report.txt").write_text(text + "\n")
    return text
