"""The paper-like figures, from one place (matplotlib, Agg: no display needed).

=========  ======================================================================  =====================
figure     what                                                                    function
=========  ======================================================================  =====================
Fig. 8     (a) the demonstrations segmented; (b) the recovered demonstrations and  :func:`fig8`
           the learned universal OE skill
Fig. 9     the demonstrated switches and the learned SS skills (arch and line)     :func:`fig9`
Fig. 10    condensed object paths for a task, mapping versus qp                   :func:`fig10`
Fig. 11    generalized switches for the T-shape and the trapezoid, dmp vs opt     :func:`fig11`
Fig. 12    a plan; planned versus executed object and tool paths                   :func:`fig12`
Fig. 14    the safety margin and the tail effect round an obstacle                 :func:`fig14`
GIF        the simulated execution: tool outline and puck                          :func:`execution_gif`
=========  ======================================================================  =====================

Each writes one file and returns its path.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from planner.plan import Plan
from planner.skills import Skills
from tools.sim.execution import Execution


def fig8(dataset: str | Path, skills: Skills, out: str | Path) -> tuple[Path, Path]:
    """Fig. 8a (``out``/fig8a_demonstrations.png) and 8b (``out``/fig8b_universal_skill.png)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from planner.oe.generalize import generalize
    from planner.plots.demonstrations import plot_demonstrations
    from planner.plots.save import save_figure
    from planner.segmentation import segment
    from problems.dataset import load_dataset

    out = Path(out)
    ds = load_dataset(dataset)
    tool = ds.tool()
    a = plot_demonstrations(ds, [segment(d, tool) for d in ds.demonstrations], tool, out / "fig8a_demonstrations.png")
    fig, ax = plt.subplots(figsize=(6, 5))
    for i, r in enumerate(skills.oe.recovered):
        ax.plot(*(1e3 * r.x).T, color="0.65", lw=0.8, label="recovered demonstrations" if i == 0 else None)
        ax.plot(*(1e3 * r.fixed).T, "k.", ms=4)
    start = np.mean([r.x[0] for r in skills.oe.recovered], axis=0)
    goal = np.mean([r.x[-1] for r in skills.oe.recovered], axis=0)
    _, x, _ = generalize(skills.oe.dmp, start, goal)
    ax.plot(*(1e3 * x).T, "r-", lw=2, label="learned universal skill (mean start and goal)")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"Fig. 8b: the universal OE skill (k = {skills.oe.k})", fontsize=9)
    ax.legend(fontsize=8)
    return a, save_figure(fig, out / "fig8b_universal_skill.png")


def fig9(dataset: str | Path, out: str | Path) -> Path:
    """Fig. 9: the dataset's demonstrated switches and the SS skills learned from them with both
    virtual object motions."""
    from planner.plots.switches import plot_learned_switches
    from planner.skills import learn_ss_from_dataset
    from planner.ss.adapter import dataset_switches

    skills = [learn_ss_from_dataset(Path(dataset), v) for v in ("arch", "line")]
    demos = [d for d in dataset_switches(dataset, faces=None) if (d.face_from, d.face_to) == skills[0].faces]
    return plot_learned_switches(demos, skills, out)


def _condensed(task_path: str | Path) -> tuple:
    """The task's tool, obstacles, margin used, target, generalized universal path (T, 2) [m] and its
    condensed push plans with the mapping and the qp variants."""
    from planner.oe.generalize import generalize
    from planner.oe.mapping_variant import MappingOptions, condense_mapping
    from planner.oe.qp_variant import condense_qp
    from planner.solve import effective_margin, qp_options, task_scene, task_skills
    from problems.task import load_task, task_obstacles, task_platform, task_tool

    task = load_task(task_path)
    tool = task_tool(task)
    platform, obstacles = task_platform(task, tool), task_obstacles(task)
    margin = effective_margin(task, obstacles)
    target = np.array(task.target)
    skills = task_skills(task, task_path, need_ss=False)
    scene = task_scene(task, obstacles, margin, skills)
    t, x, _ = generalize(skills.oe.dmp, np.array(task.start), target)
    plans = {
        "mapping (paper)": condense_mapping(t, x, tool, platform, scene, target,
                                            MappingOptions(k=task.oe.k, tube=task.oe.tube)),
        "qp": condense_qp(t, x, tool, platform, scene, target, qp_options(task)),
    }
    return task, tool, obstacles, margin, target, x, plans


def fig10(task_path: str | Path, out: str | Path) -> Path:
    """Fig. 10: the task's condensed object paths with the mapping and the qp variants."""
    from planner.plots.push_plans import plot_push_plans

    task, tool, obstacles, margin, target, _, plans = _condensed(task_path)
    return plot_push_plans(plans, tool, out, radius=task.object.radius, obstacles=obstacles, margin=margin,
                           target=target, title=task.name)


def fig11(skills: Skills, out: str | Path) -> Path:
    """Fig. 11: the SS skill generalized to the T-shape (both of its cases) and the trapezoid, with
    the ``dmp`` and ``opt`` variants and their measured penetrations."""
    from planner.plots.switches import plot_generalized_switches
    from planner.ss.cases import FIG11, fig11_task

    if skills.ss is None:
        from dmp.errors import InputError

        raise InputError("skills.ss", "an SS skill", None)
    return plot_generalized_switches(skills.ss, {name: fig11_task(name) for name in FIG11}, out)


def fig12(plan: Plan, out: str | Path, executions: Mapping[str, Execution] | None = None) -> Path:
    """Fig. 12: the plan, and planned versus executed paths for each execution given."""
    from planner.plots.execution import plot_plan

    return plot_plan(plan, out, executions)


def fig14(task_path: str | Path, out: str | Path, margins: tuple[float, ...] = (0.0, 0.005, 0.01)) -> Path:
    """Fig. 14: the outer map (7) with several safety margins round the task's first disc obstacle
    (left) and the mapping and qp condensed paths with the task's margin (right)."""
    from dmp.errors import InputError
    from planner.plots.safety_margin import plot_safety_margin
    from tools.objects import Disc

    task, _, obstacles, _, _, x, plans = _condensed(task_path)
    discs = [o for o in obstacles if isinstance(o, Disc)]
    if not discs:
        raise InputError("obstacles", "a task with a disc obstacle for Fig. 14", len(obstacles))
    return plot_safety_margin(x, discs[0], plans, out, radius=task.object.radius, margins=margins)


def execution_gif(plan: Plan, ex: Execution, out: str | Path) -> Path:
    """The animated GIF of an execution (:func:`planner.plots.execution.animate_execution`)."""
    from planner.plots.execution import animate_execution

    return animate_execution(plan, ex, out)
