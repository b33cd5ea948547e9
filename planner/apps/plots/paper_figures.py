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
README     Fig. 12 of the transfer task (plan, open and closed loop) and the       :func:`readme_figures`
           variant pairs compared, small PNGs (``make figures``)
=========  ======================================================================  =====================

Each writes one file (:func:`readme_figures` two) and returns its path. Lengths are in mm throughout.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from tooltransfer.atomic import atomic_path
from tooltransfer.planner.learning.skills import Skills
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.tools.sim.execution import Execution

if TYPE_CHECKING:
    from tooltransfer.planner.planning.setting import Setting
    from tooltransfer.problems.task import Task


def fig8(dataset: str | Path, skills: Skills, out: str | Path) -> tuple[Path, Path]:
    """Fig. 8a (``out``/fig8a_demonstrations.png) and 8b (``out``/fig8b_universal_skill.png)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tooltransfer.planner.apps.plots.demonstrations import plot_demonstrations
    from tooltransfer.planner.apps.plots.save import save_figure
    from tooltransfer.planner.learning.segmentation import segment
    from tooltransfer.planner.planning.oe.generalize import generalize
    from tooltransfer.problems.dataset import load_dataset

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
    from tooltransfer.planner.apps.plots.switches import plot_learned_switches
    from tooltransfer.planner.learning.skills import learn_ss_from_dataset
    from tooltransfer.planner.learning.switch_dataset import dataset_switches

    skills = [learn_ss_from_dataset(Path(dataset), v) for v in ("arch", "line")]
    demos = [d for d in dataset_switches(dataset, faces=None) if (d.face_from, d.face_to) == skills[0].faces]
    return plot_learned_switches(demos, skills, out)


def figure_setting(task_path: str | Path) -> tuple[Task, Skills, Setting]:
    """The task of ``task_path``, its skills (without the SS skill) and its :class:`Setting`
    (:func:`tooltransfer.planner.planning.setting.setting_from_task`, as ``solve`` builds it)."""
    from tooltransfer.planner.planning.setting import setting_from_task, task_skills
    from tooltransfer.problems.task import load_task

    task = load_task(task_path)
    skills = task_skills(task, task_path, need_ss=False)
    return task, skills, setting_from_task(task, skills, task_path)


#: Legend labels of the OE variants in Fig. 10 (a variant not named here is labelled by its name).
OE_LABELS = {"mapping": "mapping (paper)"}


def _condensed(task_path: str | Path) -> tuple:
    """The task, its setting, target, generalized universal path (T, 2) [m] and its condensed push
    plans with every OE variant (:data:`tooltransfer.planner.planning.variant_registry.OE_VARIANTS`)."""
    from tooltransfer.planner.planning.oe.generalize import generalize
    from tooltransfer.planner.planning.variant_registry import OE_VARIANTS

    task, skills, setting = figure_setting(task_path)
    target = np.array(task.target)
    t, x, _ = generalize(skills.oe.dmp, np.array(task.start), target)
    plans = {OE_LABELS.get(name, name): v.condense(t, x, setting, target, v.options_from_task(task.oe))
             for name, v in OE_VARIANTS.items()}
    return task, setting, target, x, plans


def fig10(task_path: str | Path, out: str | Path) -> Path:
    """Fig. 10: the task's condensed object paths with the mapping and the qp variants."""
    from tooltransfer.planner.apps.plots.push_plans import plot_push_plans

    task, setting, target, _, plans = _condensed(task_path)
    return plot_push_plans(plans, setting.tool, out, radius=setting.radius, obstacles=list(setting.obstacles),
                           margin=setting.margin, target=target, title=task.name)


def fig11(skills: Skills, out: str | Path) -> Path:
    """Fig. 11: the SS skill generalized to the T-shape (both of its cases) and the trapezoid, with
    the ``dmp`` and ``opt`` variants and their measured penetrations."""
    from tooltransfer.planner.apps.plots.switches import plot_generalized_switches
    from tooltransfer.planner.planning.ss.cases import FIG11, fig11_task

    if skills.ss is None:
        from tooltransfer.errors import InputError

        raise InputError("skills.ss", "an SS skill", None)
    return plot_generalized_switches(skills.ss, {name: fig11_task(name) for name in FIG11}, out)


def fig12(plan: Plan, out: str | Path, executions: Mapping[str, Execution] | None = None) -> Path:
    """Fig. 12: the plan, and planned versus executed paths for each execution given."""
    from tooltransfer.planner.apps.plots.execution import plot_plan

    return plot_plan(plan, out, executions)


def fig14(task_path: str | Path, out: str | Path, margins: tuple[float, ...] = (0.0, 0.005, 0.01)) -> Path:
    """Fig. 14: the outer map (7) with several safety margins round the task's first disc obstacle
    (left) and the mapping and qp condensed paths with the task's margin (right)."""
    from tooltransfer.errors import InputError
    from tooltransfer.planner.apps.plots.safety_margin import plot_safety_margin
    from tooltransfer.tools.objects import Disc

    _, setting, _, x, plans = _condensed(task_path)
    discs = [o for o in setting.obstacles if isinstance(o, Disc)]
    if not discs:
        raise InputError("obstacles", "a task with a disc obstacle for Fig. 14", len(setting.obstacles))
    return plot_safety_margin(x, discs[0], plans, out, radius=setting.radius, margins=margins)


def execution_gif(plan: Plan, ex: Execution, out: str | Path) -> Path:
    """The animated GIF of an execution (:func:`tooltransfer.planner.apps.plots.execution.animate_execution`)."""
    from tooltransfer.planner.apps.plots.execution import animate_execution

    return animate_execution(plan, ex, out)


#: The README's figures (``docs/images``, committed): file names, and the resolution they are drawn at.
README_FIGURES = ("fig12_transfer_tool2.png", "compare_transfer_tool2.png")
README_DPI = 100


def _palette_png(path: Path, colours: int = 128) -> Path:
    """Rewrite a PNG with an adaptive palette of ``colours`` (no dithering: the same image gives the
    same bytes), about a third of the size of the RGBA file for line drawings. The octree keeps a
    colour that few pixels have (a thin track) apart; a median cut merges it into its neighbours."""
    from PIL import Image

    with Image.open(path) as im:
        small = im.convert("RGB").quantize(colors=colours, method=Image.Quantize.FASTOCTREE,
                                           dither=Image.Dither.NONE)
    with atomic_path(path) as tmp:
        small.save(tmp, optimize=True)
    return path


def readme_figures(out: str | Path = "docs/images") -> tuple[Path, Path]:
    """The README's figures from the paper's transfer task (tool 1's demonstrations -> tool 2): every
    variant pair solved and drawn on shared axes (``compare_transfer_tool2.png``), and Fig. 12 of the
    ``qp``/``opt`` plan with its open- and closed-loop executions on the simulated Omni
    (``fig12_transfer_tool2.png``). Deterministic (the planner, the simulation and the closed loop's
    camera noise are); small palette PNGs. ``make figures`` writes them to ``docs/images``."""
    from tooltransfer.planner.apps.plots.execution import plot_plan, plot_plans
    from tooltransfer.planner.execution.closed_loop import execute_closed_loop
    from tooltransfer.planner.execution.simulate import simulate_plan
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems import PAPER_PAIRS, PAPER_TRANSFER
    from tooltransfer.problems.task import load_task

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    task = load_task(PAPER_TRANSFER)
    plans: dict[str, Plan] = {}
    for oe, ss in PAPER_PAIRS:
        variant = task.model_copy(update={"variants": task.variants.model_copy(update={"oe": oe, "ss": ss})})
        plans[f"{oe}/{ss}"] = solve(variant, PAPER_TRANSFER)
    main = plans["qp/opt"]
    if main.status != "solved":
        raise RuntimeError(f"the transfer task's qp/opt plan is {main.status}: {main.reason}")
    executions = {"open loop": simulate_plan(main).execution, "closed loop": execute_closed_loop(main).execution}
    fig12_path = _palette_png(plot_plan(main, out / README_FIGURES[0], executions, dpi=README_DPI))
    compare_path = _palette_png(plot_plans(plans, out / README_FIGURES[1], dpi=README_DPI))
    return fig12_path, compare_path


if __name__ == "__main__":  # make figures: python -m tooltransfer.planner.apps.plots.paper_figures [OUT]
    import sys
    import time

    start = time.perf_counter()
    for path in readme_figures(sys.argv[1] if len(sys.argv) > 1 else "docs/images"):
        print(f"wrote {path} ({path.stat().st_size / 1024:.0f} kB)")
    print(f"in {time.perf_counter() - start:.1f} s")
