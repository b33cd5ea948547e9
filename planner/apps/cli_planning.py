"""The command line's planning and running commands: ``paper``, ``compare``, ``tasks``, ``solve``,
``simulate``, ``export``, ``mjcf``, ``schema`` and ``tools``. Each takes the parsed arguments and returns the exit
code; :mod:`tooltransfer.planner.apps.cli` parses and dispatches. Heavy imports happen inside the commands.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

from tooltransfer.planner.apps.cli_output import file_stem, print_summary, spinner, written
from tooltransfer.planner.common.command_line import (
    EXIT_INFEASIBLE,
    EXIT_NOT_REACHED,
    EXIT_OK,
    VERDICT_EXIT,
    check_output,
)


def execute_plan(plan: object, *, closed_loop: bool, quiet: bool) -> tuple[dict[str, object], dict[str, object]]:
    """Execute a solved plan on the simulated platform open loop (and closed loop on request): the
    summary fields and the executions by mode."""
    import numpy as np

    from tooltransfer.planner.execution.simulate import simulate_plan

    with spinner("simulating open loop", quiet=quiet):
        rep = simulate_plan(plan)  # type: ignore[arg-type]
    summary: dict[str, object] = {
        "open_loop_final_error": rep.final_error, "open_loop_tool_deviation": rep.tool_deviation,
        "open_loop_tracking_error": rep.tracking_error, "open_loop_wall_time": rep.wall_time,
        "real_time_factor": float(plan.t[-1] / rep.wall_time)}  # type: ignore[attr-defined]
    executions: dict[str, object] = {"open loop": rep.execution}
    if closed_loop:
        from tooltransfer.planner.execution.closed_loop import execute_closed_loop

        with spinner("executing closed loop (re-planning from the observed puck)", quiet=quiet):
            cl = execute_closed_loop(plan)  # type: ignore[arg-type]
        executions["closed loop"] = cl.execution
        summary.update({"closed_loop_final_error": cl.final_error, "closed_loop_status": cl.status,
                        "closed_loop_reason": cl.reason, "closed_loop_pushes": cl.n_pushes,
                        "closed_loop_switches": cl.n_switches, "closed_loop_recontacts": cl.n_recontacts,
                        "closed_loop_replans": cl.n_replans,
                        "closed_loop_replan_time_median": float(np.median(cl.replan_times)) if cl.replan_times
                        else 0.0, "closed_loop_wall_time": cl.wall_time})
    return summary, executions


def cmd_paper(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.paper_run import run_paper

    print(run_paper(args.out))
    print(f"wrote the figures, plan files and report.txt to {args.out}/")
    return EXIT_OK


def cmd_compare(args: argparse.Namespace) -> int:
    import json

    from rich.console import Console
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    from tooltransfer.planner.apps.paper_run import compare

    with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), transient=True,
                  disable=args.json) as bar:
        job = bar.add_task("compare", total=None)
        table, plans = compare(args.task, args.out, lambda text: bar.update(job, description=text))
    if args.json:
        print(json.dumps({name: {"status": p.status, "reason": p.reason, "metrics": p.metrics}
                          for name, p in plans.items()}, default=float))
    else:
        Console().print(table)
        print(f"wrote the plans (plan_*.json) and the figure compare_*.png to {args.out}/")
    return EXIT_OK if plans[default_pair()].status == "solved" else EXIT_INFEASIBLE


def default_pair() -> str:
    """The variant pair a task file gets by default, ``"qp/opt"``: ``compare``'s exit code follows it (0 when
    it is solved, 1 otherwise), whatever the paper's pairs give."""
    from tooltransfer.problems.task import Variants

    default = Variants()
    return f"{default.oe}/{default.ss}"


def cmd_solve(args: argparse.Namespace) -> int:
    import json

    from tooltransfer.errors import InputError
    from tooltransfer.planner.planning.solve import check_budget, solve
    from tooltransfer.problems.task import load_task
    from tooltransfer.problems.variants import OEVariant, SSVariant, choices

    task = load_task(args.task)
    figure = None
    if args.plot:  # checked before the solve: the default is named after the task
        figure = Path(args.plot) if isinstance(args.plot, str) else (
            args.out.with_suffix(".png") if args.out else Path(f"plan_{file_stem(task.name)}.png"))
        check_output("--plot", figure, "figure")
    chosen = {"oe": args.oe, "ss": args.ss}
    if args.variant:
        oe, _, ss = args.variant.partition("/")
        if oe not in choices(OEVariant) or ss not in choices(SSVariant):
            raise InputError("--variant", f"OE/SS with OE in {{{', '.join(choices(OEVariant))}}} and SS in "
                             f"{{{', '.join(choices(SSVariant))}}}, e.g. qp/opt", args.variant)
        chosen = {"oe": args.oe or oe, "ss": args.ss or ss}
    if any(chosen.values()):
        variants = task.variants.model_copy(update={k: v for k, v in chosen.items() if v})
        task = task.model_copy(update={"variants": variants})
    check_budget(args.budget, "--budget")
    with spinner(f"planning {args.task}", quiet=args.json):
        plan = solve(task, args.task, budget=args.budget)
    if args.out:
        plan.write(args.out)
    m = plan.metrics
    summary = {"status": plan.verdict, "violated": plan.status == "violated", "reason": plan.reason,
               "variant": f"{plan.variant['oe']}/{plan.variant['ss']}",
               "pushes": " ".join(p.faces[0] for p in plan.pushes), "plan": str(args.out) if args.out else None,
               **{k: m[k] for k in ("goal_error", "cone_violation_max", "reach_violation_max", "obstacle_clearance_min",
                                    "tool_obstacle_clearance_min", "switch_clearance_min", "switch_penetration_max",
                                    "joint_limit_violation_max", "duration",
                                    "friction_cone_fraction") if k in m},  # a guided plan's share of the cone
               "planning_time": plan.planning_time,  # the solve's wall time
               "evidence": plan.evidence.get("kind"),
               # an unknown: whether its search or certificate stopped on a budget (--budget may then decide it)
               **({"budget_limited": plan.evidence["budget_limited"]} if "budget_limited" in plan.evidence else {})}
    executions: dict = {}
    if args.simulate and plan.status == "solved":
        outcome, executions = execute_plan(plan, closed_loop=True, quiet=args.json)
        summary.update(outcome)
    if args.plot and plan.status == "solved":
        from tooltransfer.planner.apps.plots.paper_figures import fig12

        with written(figure) as tmp:
            fig12(plan, tmp, executions)
        summary["figure"] = str(figure)
    elif args.plot and plan.verdict == "infeasible" and "certificate" in plan.evidence:
        from tooltransfer.planner.apps.plots.certificate import certificate_figure

        with written(figure) as tmp:
            certificate_figure(plan.evidence, plan.obstacles, tmp)
        summary["figure"] = str(figure)
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        print_summary(summary, f"{task.name}: {plan.verdict}")
    return VERDICT_EXIT[plan.verdict]


def cmd_simulate(args: argparse.Namespace) -> int:
    import json

    from tooltransfer.planner.execution.simulate import plan_to_use

    if args.viewer:  # before any work: no display, no run
        from tooltransfer.planner.execution.scene import check_viewer

        check_viewer()
    plan = plan_to_use(args.plan, args.force, "runs", "running")
    if plan is None:
        return EXIT_INFEASIBLE
    summary, executions = execute_plan(plan, closed_loop=args.closed_loop, quiet=args.json)
    if args.figure:
        from tooltransfer.planner.apps.plots.paper_figures import fig12

        with written(args.figure) as tmp:
            fig12(plan, tmp, executions)
        summary["figure"] = str(args.figure)
    if args.record:
        from tooltransfer.planner.execution.recording import write_recording

        write_recording(args.record, executions, str(args.plan))  # type: ignore[arg-type]
        summary["record"] = str(args.record)
    if args.gif:
        from tooltransfer.planner.apps.plots.paper_figures import execution_gif

        with spinner(f"writing {args.gif}", quiet=args.json), written(args.gif) as tmp:
            execution_gif(plan, list(executions.values())[-1], tmp)
        summary["gif"] = str(args.gif)
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        print_summary(summary, f"simulation of {args.plan}")
    if args.viewer:
        from tooltransfer.planner.execution.scene import replay_in_viewer

        print("replaying the plan open loop in MuJoCo's viewer (close the window to end)")
        replay_in_viewer(plan)
    return simulate_exit_code(summary, args.closed_loop)


def simulate_exit_code(summary: dict[str, object], closed_loop: bool) -> int:
    """``simulate``'s exit code for its ``summary``: :data:`EXIT_NOT_REACHED` when the closed loop was
    run and its status is not ``reached`` (the closed-loop report's own status: failed, closest,
    rounds, or a fault), else 0."""
    if closed_loop and summary.get("closed_loop_status") != "reached":
        return EXIT_NOT_REACHED
    return EXIT_OK


def cmd_export(args: argparse.Namespace) -> int:
    from tooltransfer.planner.execution.export import run_export

    return run_export(args)


def add_view_parser(sub: argparse._SubParsersAction,
                    add: Callable[..., argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """Register ``view`` and the option of ``simulate`` (registered before) that writes what ``view
    --execution`` reads, ``--record``; ``add(sub, name, help, example, func)`` makes a command."""
    sub.choices["simulate"].add_argument(
        "--record", type=Path, default=None,
        help="write the executions' object and tool paths (JSON) here, for tooltransfer view PLAN --execution FILE")
    p = add(sub, "view", "write a plan as an interactive page: the table from above, the tool and the puck "
            "animated along the plan (time slider, play), contacts, switches and re-contacts, executed paths beside "
            "the planned ones",
            "tooltransfer view out/plan.json -o out/plan.html\n"
            "  tooltransfer simulate out/plan.json --closed-loop --record out/rec.json\n"
            "  tooltransfer view out/plan.json --execution out/rec.json -o out/plan.html", cmd_view)
    p.add_argument("plan", type=Path, help="plan file (JSON)")
    p.add_argument("-o", "--out", type=Path, default=None, help="page to write (default: the plan's name ending .html)")
    p.add_argument("--execution", type=Path, default=None,
                   help="a recording of its execution (simulate --record FILE, or a simulate --json summary naming "
                   "one)")
    return p


def cmd_view(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.plots.plan_view import write_plan_view
    from tooltransfer.planner.planning.plan import read_plan

    plan = read_plan(args.plan)
    executions = None
    if args.execution is not None:
        from tooltransfer.planner.execution.recording import read_recording

        executions = read_recording(args.execution)
    out = args.out if args.out is not None else args.plan.with_suffix(".html")
    write_plan_view(plan, out, executions, title=f"plan {args.plan.name}")
    print(f"wrote {out}")
    return EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    from tooltransfer.problems.task import task_json_schema

    text = task_json_schema()
    if args.out:
        from tooltransfer.atomic import write_text

        write_text(args.out, text + "\n")
        print(f"wrote {args.out}")
    else:
        print(text)
    return EXIT_OK


def cmd_tools(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.plots.tool_library import plot_tool_library

    with written(args.out) as tmp:
        plot_tool_library(tmp)
    print(f"wrote {args.out}")
    return EXIT_OK


def task_file(value: str) -> Path:
    """A task argument: a file, or the name of a bundled task (:mod:`tooltransfer.problems.named`)."""
    from tooltransfer.problems.named import task_file

    return task_file(value)


def cmd_tasks(args: argparse.Namespace) -> int:
    from tooltransfer.problems.named import bundled_tasks, stated_outcome
    from tooltransfer.problems.task import TaskFileError
    from tooltransfer.yaml_file import read_yaml

    for name, path in bundled_tasks().items():
        doc = read_yaml(path, TaskFileError, "task file")
        text = " ".join(str(doc.get("description", "")).split()) if isinstance(doc, dict) else ""
        outcome = stated_outcome(path)
        text += f" (expected: {outcome})" if outcome else ""
        print(f"{name:34s} {text}" if not args.paths else f"{name:34s} {path}")
    return EXIT_OK


def cmd_mjcf(args: argparse.Namespace) -> int:
    from tooltransfer.atomic import write_text
    from tooltransfer.planner.execution.scene import scene_mjcf
    from tooltransfer.problems.task import load_task

    source = str(args.source)
    if source.endswith(".json"):  # a plan file: its task, the arm at the plan's first joints
        from tooltransfer.planner.planning.plan import read_plan
        from tooltransfer.problems.task import task_from_dict

        plan = read_plan(source)
        xml = scene_mjcf(task_from_dict(plan.task, f"{source}: task"), plan.joints[0] if len(plan.joints) else None)
    else:
        xml = scene_mjcf(load_task(task_file(source)))
    write_text(args.out, xml)
    print(f"wrote {args.out}")
    return EXIT_OK
