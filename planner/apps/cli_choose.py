"""The command line's ``choose``: the best tool for a task among library tools and tool files.

Exit codes: 0 a tool solves the task (the best is chosen), 1 every tool is certified infeasible, 3 no
tool solves it and some left it undecided (``unknown``), 2 bad input (an unknown tool name, a missing
or invalid tool file, a bad task or output path: a one-line message naming the argument), 130 Ctrl-C.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from tooltransfer.planner.common.command_line import VERDICT_EXIT

if TYPE_CHECKING:
    from tooltransfer.planner.apps.choose.run import Ranked

HELP = ("plan a task with each candidate tool (in parallel), execute the solved plans on the simulated platform "
        "(open and closed loop, and closed loop on a mismatched plant) and rank the tools: executed success, "
        "then margins (friction cone, contact edge, clearance), then duration. Once a plan has passed every "
        "execution, the tools whose quick first stage found no plan (in their guided search or certificate) are "
        "stopped, their verdict unknown (--wait-all waits for every verdict). Exit codes: 0 a tool solves "
        "the task, 1 every tool certified infeasible, 3 none solves it and some are unknown, 2 bad input "
        "(an unknown tool, a missing or invalid tool file, a bad task or path), 130 Ctrl-C")
EXAMPLE = ("tooltransfer choose paper/transfer_tool2 --tools finger,slope,trapezoid -o out/best.json --out out/choose\n"
           "  tooltransfer choose my_task.yaml --library --json")


def add_choose_parser(sub: argparse._SubParsersAction, add: Callable[..., argparse.ArgumentParser],
                      task_file: Callable[[str], Path]) -> argparse.ArgumentParser:
    """Register ``choose``; ``add(sub, name, help, example, func)`` makes a command."""
    p = add(sub, "choose", HELP, EXAMPLE, cmd_choose)
    p.add_argument("task", type=task_file, help="task file (YAML) or a bundled task's name (its own tool is "
                   "not a candidate unless listed)")
    which = p.add_mutually_exclusive_group()
    which.add_argument("--tools", default=None, help="candidate tools, comma-separated: library names "
                       "(tooltransfer tools) and tool files (YAML paths)")
    which.add_argument("--library", action="store_true", help="every library tool (the default)")
    p.add_argument("-o", dest="best", type=Path, default=None, metavar="BEST.json",
                   help="write the best tool's plan (plan format) here")
    p.add_argument("--out", type=Path, default=None, metavar="DIR",
                   help="write the candidates' plans side by side (choose.png) and every solved plan here")
    p.add_argument("--json", action="store_true", help="print a JSON summary (its \"ranking\" lists every tool)")
    p.add_argument("--workers", type=int, default=2,
                   help="cores (default 2; at most the CPU count): a process per tool, up to 4 per core, share them")
    p.add_argument("--execute-all", action="store_true",
                   help="execute every solved plan (default: until the best is known)")
    p.add_argument("--wait-all", action="store_true",
                   help="wait for every tool's verdict (default: once a plan has passed every execution, the tools "
                   "in their slower stages, the guided search or the certificate, are stopped and reported unknown)")
    p.add_argument("--seed", type=int, default=0, help="camera-noise seed of the closed loops")
    return p


def cmd_choose(args: argparse.Namespace) -> int:
    import json

    from tooltransfer.errors import InputError
    from tooltransfer.planner.apps.choose.candidates import tool_arguments
    from tooltransfer.planner.apps.choose.report import summary, table
    from tooltransfer.planner.apps.choose.run import choose_tool
    from tooltransfer.planner.apps.cli_output import file_stem, spinner, written
    from tooltransfer.problems.task import load_task

    tools = None if args.tools is None else tool_arguments(args.tools, "--tools")
    if args.workers < 1:
        raise InputError("--workers", "a whole number >= 1", args.workers)
    task = load_task(args.task)
    if tools is not None:  # every tool checked (and named as the option) before any planning
        from tooltransfer.planner.apps.choose.candidates import candidates

        candidates(task, tools, field="--tools")
    status = spinner(f"choosing a tool for {args.task}", quiet=args.json)
    with status as s:  # type: ignore[attr-defined]
        def progress(text: str) -> None:
            if s is not None:
                s.update(f"choosing a tool for {args.task}: {text}")

        choice = choose_tool(task, tools, workers=args.workers, execute_all=args.execute_all,
                             wait_all=args.wait_all, seed=args.seed, progress=progress)
    plan_path = figure = None
    if args.best is not None and choice.plan is not None:
        choice.plan.write(args.best)
        plan_path = str(args.best)
    if args.out is not None:
        from tooltransfer.planner.apps.plots.execution import plot_plans

        args.out.mkdir(parents=True, exist_ok=True)
        shown = {_panel_title(r): r.plan for r in choice.ranking if r.plan is not None}
        if shown:
            path = args.out / f"choose_{file_stem(task.name)}.png"
            with written(path) as tmp:
                plot_plans(shown, tmp)
            figure = str(path)
        for r in choice.ranking:
            if r.verdict == "solved" and r.plan is not None:
                r.plan.write(args.out / f"plan_{file_stem(r.label)}.json")
    out = summary(choice, plan_path, figure)
    if args.json:
        print(json.dumps(out, default=float))
    else:
        from rich.console import Console

        con = Console()
        if not con.is_terminal:
            con.width = 200  # files and pipes: whole rows
        con.print(table(choice))
        if plan_path:
            print(f"wrote the best plan ({choice.best.label}) to {plan_path}")  # type: ignore[union-attr]
        if figure:
            print(f"wrote the candidates side by side to {figure} and the solved plans to {args.out}/")
        print(f"chose in {choice.wall:.1f} s (CPU {choice.cpu:.1f} s)")
    return VERDICT_EXIT[choice.verdict]


def _panel_title(r: Ranked) -> str:
    """A candidate's panel title in the side-by-side figure: rank, tool, verdict and, for an executed
    plan, its closed loop's final error."""
    closed = r.executions.closed_loop if r.executions is not None else None
    tail = f"; closed loop {1e3 * closed:.2f} mm" if closed is not None else ""
    return f"{r.rank}. {r.label} ({r.verdict}{tail})"
