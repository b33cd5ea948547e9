"""The paper's transfer scenario (``tooltransfer paper``, the job of ``make demo``) and ``tooltransfer compare``.

``compare``: solve a task with every variant pair (OE ``mapping``/``qp`` x SS ``dmp``/``opt``), write
the plans, one figure with a panel per pair and a table of the shared metrics.

``run_paper``: the paper's transfer scenario end to end: learn the skills from the committed
demonstrations (``problems/data/finger_demos``) into a skills file, compare the variants on the
transfer to tool 2 (``problems/paper/transfer_tool2.yaml``), execute the ``qp``/``opt`` plan on the
simulated platform open loop (as the paper did) and closed loop (re-planning from the observed
puck), and write every figure (Figs. 8-12, 14 and a GIF of the execution), plan and report to the
output folder.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path

from tooltransfer.atomic import write_text
from tooltransfer.planner.common.metric_units import display
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.problems import FINGER_DEMOS, PAPER_PAIRS, PAPER_TRANSFER
from tooltransfer.problems.task import load_task

ROOT = Path(__file__).resolve().parents[2]
DATASET = FINGER_DEMOS

def _row(key: str, label: str, shown_as: str | None = None) -> tuple[str, str, str, float]:
    """A row of :data:`ROWS`: metric ``key``, ``label``, and the unit and scale it is shown in
    (:func:`tooltransfer.planner.common.metric_units.display`: lengths in mm; ``shown_as`` another unit)."""
    unit, scale = display(key, shown_as)
    return key, label, unit, scale


#: Rows of the comparison table: metric key, label, unit, scale (from SI to the unit; units from
#: :data:`tooltransfer.planner.common.metric_units.UNITS`, the stages' times in ms).
ROWS = (
    ("status", "status", "", 1.0),
    _row("n_pushes", "pushes"),
    _row("goal_error", "goal error"),
    _row("cone_violation_max", "cone violation"),
    _row("reach_violation_max", "reach violation"),
    _row("obstacle_clearance_min", "object-obstacle clearance"),
    _row("tool_obstacle_clearance_min", "tool-obstacle clearance"),
    _row("deviation_mean", "mean deviation from skill"),
    _row("switch_clearance_min", "switch clearance (middle)"),
    _row("switch_penetration_max", "switch penetration"),
    _row("joint_limit_violation_max", "joint-limit violation"),
    _row("duration", "duration"),
    _row("time_oe", "time: OE", "ms"),
    _row("time_switches_and_timing", "time: switches + timing", "ms"),
)


#: Plan statuses in the order they are counted (``violated``: a whole plan that breaks a hard check).
STATUS_ORDER = ("solved", "violated", "infeasible")
_STATUS_STYLE = {"solved": "", "violated": "yellow", "infeasible": "red"}


def status_counts(plans: dict[str, Plan]) -> str:
    """The plans counted by status, each apart: e.g. ``"solved 2, violated 1, infeasible 1"``; a violated
    plan names the hard-check families it breaks (its reason)."""
    from collections import Counter

    c = Counter(p.status for p in plans.values())
    order = [*STATUS_ORDER, *sorted(set(c) - set(STATUS_ORDER))]
    return ", ".join(f"{s} {c[s]}" for s in order if c[s] or s in STATUS_ORDER)


def metrics_table(plans: dict[str, Plan], title: str = "") -> object:
    """A rich table of the shared metrics, one column per plan; the caption counts the plans by
    status (:func:`status_counts`) and names what each violated plan breaks."""
    from rich.markup import escape
    from rich.table import Table

    caption = [f"plans: {status_counts(plans)}"]
    caption += [f"{name} violated: {escape(p.reason.removeprefix('hard checks violated: '))}"
                for name, p in plans.items() if p.status == "violated"]
    table = Table(title=title or None, title_justify="left", caption="\n".join(caption), caption_justify="left")
    table.add_column("metric")
    for name in plans:
        table.add_column(name, justify="right")
    for key, label, unit, scale in ROWS:
        cells = []
        for p in plans.values():
            if key == "status":
                style = _STATUS_STYLE.get(p.status, "red")
                cells.append(f"[{style}]{p.status}[/{style}]" if style else p.status)
                continue
            v = p.metrics.get(key)
            cells.append("-" if v is None else f"{scale * v:.4g}")
        table.add_row(f"{label} \\[{unit}]" if unit else label, *cells)
    return table


def render(renderable: object, width: int = 120) -> str:
    """Plain text of a rich renderable (for report files)."""
    from rich.console import Console

    buf = io.StringIO()
    Console(file=buf, width=width, color_system=None).print(renderable)
    return buf.getvalue()


def compare(
    task_path: Path, out: Path, step: Callable[[str], None] = lambda _s: None
) -> tuple[object, dict[str, Plan]]:
    """Solve ``task_path`` with every variant pair (:data:`tooltransfer.problems.PAPER_PAIRS`); write the plans
    (``plan_<task>_<oe>_<ss>.json``) and ``compare_<task>.png`` to ``out``; return the metrics table
    (rich) and the plans. ``step`` is called with a description before each solve (progress)."""
    from tooltransfer.planner.apps.plots.execution import plot_plans
    from tooltransfer.planner.planning.solve import solve

    task = load_task(task_path)
    out.mkdir(parents=True, exist_ok=True)
    plans: dict[str, Plan] = {}
    for oe, ss in PAPER_PAIRS:
        step(f"solve {task.name} with oe {oe}, ss {ss}")
        t = task.model_copy(update={"variants": task.variants.model_copy(update={"oe": oe, "ss": ss})})
        plans[f"{oe}/{ss}"] = plan = solve(t, task_path)
        plan.write(out / f"plan_{task.name}_{oe}_{ss}.json")
    step("draw the comparison")
    plot_plans(plans, out / f"compare_{task.name}.png")
    return metrics_table(plans, f"{task.name}: variant pairs (oe/ss)"), plans


def run_paper(out: Path) -> str:
    """Run the main job; returns the report text (also written to ``out/report.txt``)."""
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    from tooltransfer.planner.apps.plots import paper_figures as figures
    from tooltransfer.planner.execution.closed_loop import execute_closed_loop
    from tooltransfer.planner.execution.simulate import simulate_plan
    from tooltransfer.planner.learning.skills import Skills, learn_skills

    out.mkdir(parents=True, exist_ok=True)
    report: list[str] = []
    with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), transient=True) as bar:
        job = bar.add_task("learn", total=None)

        def step(text: str) -> None:
            bar.update(job, description=text)

        step("learn the OE and SS skills from the demonstrations")
        skills_file = learn_skills(DATASET).save(out / "skills.json")
        skills = Skills.load(skills_file)
        report.append(f"skills learned from {DATASET.relative_to(ROOT)} -> {skills_file}")
        table, plans = compare(PAPER_TRANSFER, out, step)
        report.append(render(table))
        main = plans["qp/opt"]
        executions = {}
        if main.status == "solved":
            step("simulate the qp/opt plan open loop")
            sim = simulate_plan(main)
            executions["open loop"] = sim.execution
            report.append(
                f"qp/opt plan, open loop on the simulated Omni: final object error {1e3 * sim.final_error:.1f} mm, "
                f"largest tool deviation {1e3 * sim.tool_deviation:.2f} mm, {main.t[-1]:.1f} s plan simulated in "
                f"{sim.wall_time:.2f} s ({main.t[-1] / sim.wall_time:.0f}x real time)")
            step("simulate the qp/opt plan closed loop (re-planning from the observed puck)")
            closed = execute_closed_loop(main)
            executions["closed loop"] = closed.execution
            report.append(
                f"qp/opt plan, closed loop: final object error {1e3 * closed.final_error:.1f} mm after "
                f"{closed.n_pushes} pushes ({closed.status}{': ' + closed.reason if closed.reason else ''})")
            step("draw Fig. 12 and the execution GIF")
            report.append(f"wrote {figures.fig12(main, out / 'fig12_plan_and_execution.png', executions)}")
            report.append(f"wrote {figures.execution_gif(main, executions['closed loop'], out / 'execution.gif')}")
        step("draw Figs. 8-11 and 14")
        a, b = figures.fig8(DATASET, skills, out)
        report.append(f"wrote {a}\nwrote {b}")
        report.append(f"wrote {figures.fig9(DATASET, out / 'fig9_switching_skills.png')}")
        report.append(f"wrote {figures.fig10(PAPER_TRANSFER, out / 'fig10_condensed_paths.png')}")
        report.append(f"wrote {figures.fig11(skills, out / 'fig11_generalized_switches.png')}")
        fig14_task = ROOT / "problems" / "paper" / "fig14_safety_margin.yaml"
        report.append(f"wrote {figures.fig14(fig14_task, out / 'fig14_safety_margin.png')}")
    text = "\n".join(report)
    write_text(out / "report.txt", text + "\n")
    return text
