"""The ``tooltransfer`` command line.

Exit codes: 0 done (solved), 1 infeasible, 2 bad input (a one-line message naming the file and the
field, or the option and the path, never a traceback: ``-v`` adds it for a bug report), 130
stopped by Ctrl-C (one line), 141 when the output's reader has gone (``| head``: silently). Output
paths are checked before any work (a folder where a file is expected, a missing folder, a place
that cannot be written: exit 2 naming the option), and every file is written atomically
(:mod:`tooltransfer.atomic`). Every command has ``--help`` with an example.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

# nothing heavy is imported before main() runs: a Ctrl-C while numpy and the rest load is caught too
from tooltransfer.planner.common.command_line import (
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    EXIT_INFEASIBLE,
    EXIT_INTERRUPTED,
    EXIT_OK,
    check_output,
    missing_extra,
)

#: The tools command's default figure (its folder is made when missing; an explicit path's must exist).
DEFAULT_TOOLS_FIGURE = Path("out/tools.png")


def _spinner(text: str, quiet: bool = False) -> object:
    """A progress display for a step that takes more than a second (nothing when ``quiet``)."""
    import contextlib

    if quiet:
        return contextlib.nullcontext()
    from rich.console import Console

    return Console(stderr=True).status(text)


def _print_summary(summary: dict[str, object], title: str) -> None:
    """A two-column rich table of a summary, each number with its unit from
    :data:`tooltransfer.planner.common.metric_units.UNITS` (lengths in m are printed in mm)."""
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    from tooltransfer.planner.common.metric_units import shown

    table = Table(title=title, title_justify="left", show_header=False)
    table.add_column("key")
    table.add_column("value", justify="right")
    for k, v in summary.items():
        if isinstance(v, float):
            label, text = shown(k, v)
            table.add_row(escape(label), text)
        else:
            table.add_row(k, str(v))
    Console().print(table)


def _execute(plan: object, *, closed_loop: bool, quiet: bool) -> tuple[dict[str, object], dict[str, object]]:
    """Execute a solved plan on the simulated platform open loop (and closed loop on request): the
    summary fields and the executions by mode."""
    import numpy as np

    from tooltransfer.planner.execution.simulate import simulate_plan

    with _spinner("simulating open loop", quiet=quiet):
        rep = simulate_plan(plan)  # type: ignore[arg-type]
    summary: dict[str, object] = {
        "open_loop_final_error": rep.final_error, "open_loop_tool_deviation": rep.tool_deviation,
        "open_loop_tracking_error": rep.tracking_error, "open_loop_wall_time": rep.wall_time,
        "real_time_factor": float(plan.t[-1] / rep.wall_time)}  # type: ignore[attr-defined]
    executions: dict[str, object] = {"open loop": rep.execution}
    if closed_loop:
        from tooltransfer.planner.execution.closed_loop import execute_closed_loop

        with _spinner("executing closed loop (re-planning from the observed puck)", quiet=quiet):
            cl = execute_closed_loop(plan)  # type: ignore[arg-type]
        executions["closed loop"] = cl.execution
        summary.update({"closed_loop_final_error": cl.final_error, "closed_loop_status": cl.status,
                        "closed_loop_reason": cl.reason, "closed_loop_pushes": cl.n_pushes,
                        "closed_loop_switches": cl.n_switches, "closed_loop_recontacts": cl.n_recontacts,
                        "closed_loop_replans": cl.n_replans,
                        "closed_loop_replan_time_median": float(np.median(cl.replan_times)) if cl.replan_times
                        else 0.0, "closed_loop_wall_time": cl.wall_time})
    return summary, executions


def _cmd_paper(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.paper_run import run_paper

    print(run_paper(args.out))
    print(f"wrote the figures, plan files and report.txt to {args.out}/")
    return EXIT_OK


def _cmd_compare(args: argparse.Namespace) -> int:
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
    return EXIT_OK if all(p.status == "solved" for p in plans.values()) else EXIT_INFEASIBLE


def _cmd_demos(args: argparse.Namespace) -> int:
    import time

    t0 = time.perf_counter()
    if args.calibration:
        from tooltransfer.planner.apps.operator.calibration import generate_calibration
        from tooltransfer.problems.dataset import load_meta

        out = generate_calibration(args.out, seed=args.seed, tool=args.tool)
        n = len(load_meta(out).demonstrations)
        print(f"wrote a calibration recording ({n} trials of straight pushes) to {out} in "
              f"{time.perf_counter() - t0:.1f} s")
        return EXIT_OK
    from tooltransfer.planner.apps.operator.generate import generate_demonstrations

    out = generate_demonstrations(args.out, n=args.n, seed=args.seed, tool=args.tool)
    print(f"wrote {args.n} demonstrations to {out} in {time.perf_counter() - t0:.1f} s")
    return EXIT_OK


def _cmd_learn(args: argparse.Namespace) -> int:
    import time

    from tooltransfer.planner.learning.skills import learn_skills

    t0 = time.perf_counter()
    skills = learn_skills(args.dataset, k=args.k, virtual=args.virtual, calibration=args.calibration)
    path = skills.save(args.out)
    ss = skills.ss
    assert ss is not None  # learn_skills(with_ss=True)
    print(f"learned from {args.dataset} in {time.perf_counter() - t0:.1f} s: OE skill (k = {skills.oe.k}, "
          f"{len(skills.oe.recovered)} recovered demonstrations), SS skill ({ss.faces[0]} -> {ss.faces[1]}, "
          f"{ss.n_demos} switches, virtual motion {ss.virtual!r}); wrote {path}")
    m, info = skills.mechanics, skills.identification
    if m is not None and info is not None:
        print(f"push mechanics from {info['n_pushes']} pushes of {info['dataset']} ({info['kind']}): "
              f"mu = {m.mu:.3f} +- {m.mu_std:.3f}, c = {m.c:.3f} +- {m.c_std:.3f}; predicted end positions "
              f"within {1e3 * info['end_error_median']:.2f} mm (median), {1e3 * info['end_error_p90']:.2f} mm (p90)")
        if info["message"]:
            print(f"note: {info['message']}")
    return EXIT_OK


def _cmd_segment(args: argparse.Namespace) -> int:
    import numpy as np

    from tooltransfer.planner.learning.segmentation import load_fixed_points, segment
    from tooltransfer.problems.dataset import load_dataset

    ds = load_dataset(args.dataset)
    tool = ds.tool()
    fixed = {} if args.fixed_points is None else load_fixed_points(args.fixed_points,
                                                                    [d.name for d in ds.demonstrations])
    segs = [segment(d, tool, radius=float(ds.meta.object_radius), fixed_points=fixed.get(d.name))
            for d in ds.demonstrations]
    for d, s in zip(ds.demonstrations, segs, strict=True):
        faces = " ".join(f"{p.face}[{p.t_start:.2f}-{p.t_end:.2f}]" for p in s.pushes)
        corners = ", ".join(f"({x:.4f}, {y:.4f})" for x, y in np.asarray(s.fixed_points))
        print(f"{d.name}: {len(s.pushes)} pushes, {len(s.switches)} switches "
              f"({', '.join(f'{w.face_from}->{w.face_to}' for w in s.switches)}), fixed points [m]: {corners}")
        if args.verbose:
            print(f"    {faces}")
    if args.figure:
        from tooltransfer.planner.apps.plots.demonstrations import plot_demonstrations

        with _written(args.figure) as tmp:
            plot_demonstrations(ds, segs, tool, tmp)
        print(f"wrote {args.figure}")
    return EXIT_OK


def _cmd_solve(args: argparse.Namespace) -> int:
    import json

    from tooltransfer.errors import InputError
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task
    from tooltransfer.problems.variants import OEVariant, SSVariant, choices

    task = load_task(args.task)
    figure = None
    if args.plot:  # checked before the solve: the default is named after the task
        figure = Path(args.plot) if isinstance(args.plot, str) else (
            args.out.with_suffix(".png") if args.out else Path(f"plan_{file_stem(task.name)}.png"))
        check_output("--plot", figure)
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
    with _spinner(f"planning {args.task}", quiet=args.json):
        plan = solve(task, args.task)
    if args.out:
        plan.write(args.out)
    m = plan.metrics
    summary = {"status": plan.status, "reason": plan.reason, "variant": f"{plan.variant['oe']}/{plan.variant['ss']}",
               "pushes": " ".join(p.faces[0] for p in plan.pushes), "plan": str(args.out) if args.out else None,
               **{k: m[k] for k in ("goal_error", "cone_violation_max", "reach_violation_max", "obstacle_clearance_min",
                                    "tool_obstacle_clearance_min", "switch_clearance_min", "switch_penetration_max",
                                    "joint_limit_violation_max", "duration") if k in m},
               # the solve's wall time; a plan that stopped early has no time_total: the stages it ran
               "planning_time": m.get("time_total", sum(v for k, v in m.items() if k.startswith("time_")))}
    executions: dict = {}
    if args.simulate and plan.status == "solved":
        outcome, executions = _execute(plan, closed_loop=True, quiet=args.json)
        summary.update(outcome)
    if args.plot and plan.status == "solved":
        from tooltransfer.planner.apps.plots.paper_figures import fig12

        with _written(figure) as tmp:
            fig12(plan, tmp, executions)
        summary["figure"] = str(figure)
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        _print_summary(summary, f"{task.name}: {plan.status}")
    return EXIT_OK if plan.status == "solved" else EXIT_INFEASIBLE


def _cmd_simulate(args: argparse.Namespace) -> int:
    import json

    from tooltransfer.planner.execution.simulate import plan_to_use

    plan = plan_to_use(args.plan, args.force, "runs", "running")
    if plan is None:
        return EXIT_INFEASIBLE
    summary, executions = _execute(plan, closed_loop=args.closed_loop, quiet=args.json)
    if args.figure:
        from tooltransfer.planner.apps.plots.paper_figures import fig12

        with _written(args.figure) as tmp:
            fig12(plan, tmp, executions)
        summary["figure"] = str(args.figure)
    if args.gif:
        from tooltransfer.planner.apps.plots.paper_figures import execution_gif

        with _spinner(f"writing {args.gif}", quiet=args.json), _written(args.gif) as tmp:
            execution_gif(plan, list(executions.values())[-1], tmp)
        summary["gif"] = str(args.gif)
    if args.json:
        print(json.dumps(summary, default=float))
    else:
        _print_summary(summary, f"simulation of {args.plan}")
    return EXIT_OK


def _cmd_export(args: argparse.Namespace) -> int:
    from tooltransfer.planner.execution.export import run_export

    return run_export(args)


def _cmd_schema(args: argparse.Namespace) -> int:
    from tooltransfer.problems.task import task_json_schema

    text = task_json_schema()
    if args.out:
        from tooltransfer.atomic import write_text

        write_text(args.out, text + "\n")
        print(f"wrote {args.out}")
    else:
        print(text)
    return EXIT_OK


def _cmd_tools(args: argparse.Namespace) -> int:
    from tooltransfer.planner.apps.plots.tool_library import plot_tool_library

    with _written(args.out) as tmp:
        plot_tool_library(tmp)
    print(f"wrote {args.out}")
    return EXIT_OK


@contextmanager
def _written(path: Path) -> Iterator[Path]:
    """A temporary path beside ``path`` for a writer that takes a path (a figure): it replaces
    ``path`` once the writer is done, and is removed if the writer fails
    (:func:`tooltransfer.atomic.atomic_path`)."""
    from tooltransfer.atomic import atomic_path

    with atomic_path(path) as tmp:
        yield tmp


def file_stem(name: str, limit: int = 100) -> str:
    """``name`` made a safe file-name stem: letters, digits, ``.``, ``_`` and ``-`` kept, anything
    else (``/``, ``..``, spaces, control characters) one ``_``, at most ``limit`` characters, never
    empty or starting with a dot."""
    stem = re.sub(r"[^A-Za-z0-9._-]+", "_", name)[:limit].lstrip(".") or "task"
    return stem


#: Output options by command: (argument name, option as shown, kind; see :func:`check_output`).
OUTPUTS: dict[str, tuple[tuple[str, str, str], ...]] = {
    "solve": (("out", "-o/--out", "file"), ("plot", "--plot", "file")),
    "learn": (("out", "-o/--out", "file"),),
    "simulate": (("figure", "--figure", "file"), ("gif", "--gif", "file")),
    "export": (("out", "-o/--out", "file"),),
    "segment": (("figure", "--figure", "file"),),
    "schema": (("out", "--out", "file"),),
    "tools": (("out", "--out", "file"),),
    "compare": (("out", "--out", "folder"),),
    "paper": (("out", "--out", "folder"),),
    "demos": (("out", "--out", "folder"),),
    "batch generate": (("out", "--out", "folder"),),
    "batch run": (("db", "--db", "store"),),
    "batch report": (("out", "--out", "folder"),),
}


def _check_outputs(args: argparse.Namespace) -> None:
    command = args.command + (f" {args.batch_command}" if args.command == "batch" else "")
    for dest, option, kind in OUTPUTS.get(command, ()):
        value = getattr(args, dest, None)
        if not isinstance(value, str | Path):
            continue
        if kind == "store":  # a results file (SQLite): the store makes its folders
            check_output(option, Path(value), "file", make_folders=True)
        else:
            default = command == "tools" and Path(value) == DEFAULT_TOOLS_FIGURE
            check_output(option, Path(value), kind, make_folders=default)


def _message(exc: BaseException) -> str:
    """The error's message on one line, a long value in it cut (the field and the file stay)."""
    from tooltransfer.errors import InputError
    from tooltransfer.yaml_file import clip

    text = str(exc)
    if isinstance(exc, InputError) and exc.got is not None:
        got = str(exc.got)
        if len(got) > 100 and text == f"{exc.field}: expected {exc.expected}, got {got}":
            text = f"{clip(exc.field, 300)}: expected {exc.expected}, got {clip(got)}"
    return clip(text, 2000)


def _file_in_traceback(tb: object) -> str | None:
    """The file a failing reader had open: a path-like local of the innermost frame that has one."""
    frames = []
    while tb is not None:
        frames.append(tb.tb_frame)  # type: ignore[attr-defined]
        tb = tb.tb_next  # type: ignore[attr-defined]
    for frame in reversed(frames):
        for name in ("p", "path", "file", "filename", "fname", "tool_path", "meta_path"):
            v = frame.f_locals.get(name)
            if isinstance(v, str | Path) and str(v) and os.path.isfile(v):
                return str(v)
    return None


def _unexpected(exc: BaseException) -> str:
    """One line for an exception no check caught (a resource, a file, or a bug)."""
    if isinstance(exc, UnicodeError):
        where = _file_in_traceback(exc.__traceback__)
        return (f"{where or 'a file'}: <file>: expected UTF-8 text, got bytes that are not UTF-8 "
                f"({type(exc).__name__}: {str(exc)[:100]})")
    if isinstance(exc, OSError):
        return f"{exc.filename or 'a file'}: {exc.strerror or exc}" + (f" -> {exc.filename2}" if exc.filename2 else "")
    if isinstance(exc, MemoryError):
        return "out of memory (an input beyond the bounds the checks know of; -v shows where)"
    if isinstance(exc, RecursionError):
        return "an input nested too deeply (-v shows where)"
    return f"internal error, a bug (-v shows the traceback for a report): {type(exc).__name__}: {exc}"



def _task_file(value: str) -> Path:
    """A task argument: a file, or the name of a bundled task (:mod:`tooltransfer.problems.named`)."""
    from tooltransfer.problems.named import task_file

    return task_file(value)


def _cmd_tasks(args: argparse.Namespace) -> int:
    from tooltransfer.problems.named import bundled_tasks
    from tooltransfer.problems.task import TaskFileError
    from tooltransfer.yaml_file import read_yaml

    for name, path in bundled_tasks().items():
        doc = read_yaml(path, TaskFileError, "task file")
        text = " ".join(str(doc.get("description", "")).split()) if isinstance(doc, dict) else ""
        if not text:  # the hard cases say what they are in their first comment line
            comments = [ln.lstrip("# ").strip() for ln in path.read_text(encoding="utf-8").splitlines()
                        if ln.startswith("#")]
            text = comments[0] if comments else ""
        print(f"{name:34s} {text[:120]}" if not args.paths else f"{name:34s} {path}")
    return EXIT_OK


def _add(sub: argparse._SubParsersAction, name: str, helptext: str, example: str,
         func: Callable[[argparse.Namespace], int]) -> argparse.ArgumentParser:
    p = sub.add_parser(name, help=helptext, description=helptext, epilog=f"example:\n  {example}",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.set_defaults(func=func)
    p.add_argument("-v", "--verbose", action="store_true",
                   help="on an error or Ctrl-C also print the traceback (for a bug report)"
                   + ("; list every push with its interval [s]" if name == "segment" else ""))
    return p


class _Version(argparse.Action):
    """``--version``: the distribution's version, looked up only when asked (importing
    importlib.metadata would slow every other command down; ``benchmarks/README.md``)."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser: argparse.ArgumentParser, *args: Any, **kwargs: Any) -> None:
        import tooltransfer

        print(f"tooltransfer {tooltransfer.__version__}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    from tooltransfer.problems.variants import MAPPING_K, VIRTUAL_MOTION, OEVariant, SSVariant, VirtualMotion, choices

    parser = argparse.ArgumentParser(
        prog="tooltransfer", description="DMP skill transfer for multi-tool pushing on a Phantom Omni."
    )
    parser.add_argument("--version", action=_Version, help="print the installed version and exit")
    sub = parser.add_subparsers(dest="command", required=True)
    p = _add(sub, "paper", "the paper's transfer scenario (the job of `make demo`): learn from the committed "
             "demonstrations, compare the variants on the transfer to tool 2, simulate the qp plan",
             "tooltransfer paper --out out", _cmd_paper)
    p.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    p = _add(sub, "compare", "solve a task with every variant pair (oe mapping|qp x ss dmp|opt): a metrics table "
             "and one figure", "tooltransfer compare problems/paper/transfer_tool2.yaml --out out", _cmd_compare)
    p.add_argument("task", type=_task_file, help="task file (YAML) or a bundled task's name (tooltransfer tasks)")
    p.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    p.add_argument("--json", action="store_true", help="print every plan's status and metrics as JSON")
    p = _add(sub, "demos", "generate demonstrations (or a calibration recording) with the scripted operator on the "
             "simulated Omni", "tooltransfer demos --tool finger --n 8 --seed 0 --out problems/data/finger_demos\n"
             "  tooltransfer demos --calibration --out out/calibration", _cmd_demos)
    p.add_argument("--tool", default="finger", help="demonstration tool (tool 1)")
    p.add_argument("--n", type=int, default=8, help="number of demonstrations (not used with --calibration)")
    p.add_argument("--calibration", action="store_true",
                   help="record a calibration instead: straight pushes at 0, +-15, +-30, +-45 deg off each face's "
                   "normal and +-80 deg on the longest face, for identifying the push mechanics (README)")
    p.add_argument("--seed", type=int, default=0, help="seed (generation is deterministic for it)")
    p.add_argument("--out", type=Path, required=True, help="dataset folder to write")
    p = _add(sub, "learn", "learn the OE and SS skills from a demonstration dataset into one skills file",
             "tooltransfer learn problems/data/finger_demos -o out/skills.json\n"
             "  tooltransfer learn problems/data/finger_demos --calibration out/calibration -o out/skills.json",
             _cmd_learn)
    p.add_argument("dataset", type=Path, help="dataset folder (meta.yaml and CSVs)")
    p.add_argument("-o", "--out", type=Path, required=True, help="skills file to write (JSON)")
    p.add_argument("--k", type=float, default=MAPPING_K, help="adjusting factor of the mappings (6)-(7), in (0, 1)")
    p.add_argument("--virtual", choices=choices(VirtualMotion), default=VIRTUAL_MOTION,
                   help="virtual object motion of the SS skill")
    p.add_argument("--calibration", type=Path, default=None,
                   help="identify the push mechanics from this calibration recording (tooltransfer demos "
                   "--calibration) instead of the dataset's pushes")
    p = _add(sub, "segment", "segment a dataset into pushes and switches (and draw it)",
             "tooltransfer segment problems/data/finger_demos --figure out/demos.png", _cmd_segment)
    p.add_argument("dataset", type=Path, help="dataset folder (meta.yaml and CSVs, see the README)")
    p.add_argument("--figure", type=Path, default=None, help="write the figure (Figs. 4b/8a style) here")
    p.add_argument("--fixed-points", type=Path, default=None,
                   help="JSON file {demo name: [[x, y], ...]} [m] overriding the automatic corners")
    p = _add(sub, "tasks", "list the bundled task files by name (solve and compare take a name or a file)",
             "tooltransfer tasks\n  tooltransfer solve paper/transfer_tool2", _cmd_tasks)
    p.add_argument("--paths", action="store_true", help="print each task's file instead of its description")
    p = _add(sub, "solve", "plan a task file: pushes, switches, approach, timing, joints",
             "tooltransfer solve problems/paper/transfer_tool2.yaml -o out/plan.json", _cmd_solve)
    p.add_argument("task", type=_task_file, help="task file (YAML) or a bundled task's name (tooltransfer tasks)")
    p.add_argument("-o", "--out", type=Path, default=None, help="write the plan (JSON) here")
    p.add_argument("--oe", choices=choices(OEVariant), default=None, help="override the task's OE variant")
    p.add_argument("--ss", choices=choices(SSVariant), default=None, help="override the task's switch variant")
    p.add_argument("--variant", default=None, help="override both as OE/SS, e.g. qp/opt or mapping/dmp")
    p.add_argument("--plot", nargs="?", const=True, default=None,
                   help="draw the plan (Fig. 12; with --simulate also the executions) to PATH (default: next to -o)")
    p.add_argument("--simulate", action="store_true",
                   help="execute the plan on the simulated platform, open loop and closed loop")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p = _add(sub, "simulate", "execute a plan file on the simulated platform (open loop, and closed loop on request)",
             "tooltransfer simulate out/plan.json --closed-loop --figure out/fig12.png --gif out/run.gif",
             _cmd_simulate)
    p.add_argument("plan", type=Path, help="plan file (JSON)")
    p.add_argument("--closed-loop", action="store_true",
                   help="also execute closed loop (re-plan the corners from the observed puck)")
    p.add_argument("--figure", type=Path, default=None, help="write planned versus executed paths (Fig. 12) here")
    p.add_argument("--gif", type=Path, default=None, help="write an animated GIF of the (last) execution here")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--force", action="store_true", help="run a plan that fails its checks against itself and its "
                   "task (or a violated plan) anyway, with a warning")
    p = _add(sub, "export", "write a plan's joint trajectory (positions, velocities, accelerations) for a real arm: "
             "CSV, NumPy .npz or a ROS JointTrajectory as JSON",
             "tooltransfer export out/plan.json --format joint-trajectory -o out/plan.trajectory.json", _cmd_export)
    p.add_argument("plan", type=Path, help="plan file (JSON)")
    p.add_argument("--format", choices=("csv", "npz", "joint-trajectory"), required=True, help="what to write")
    p.add_argument("-o", "--out", type=Path, default=None,
                   help="file to write (default: the plan's name ending .csv, .npz or .trajectory.json)")
    p.add_argument("--joint-names", default=None, help="the joints' names for the robot, comma-separated "
                   "(default: the plan's, q1,q2,q3)")
    p.add_argument("--force", action="store_true", help="export a plan that fails its checks against itself and "
                   "its task (or a violated plan) anyway, with a warning")
    p = _add(sub, "schema", "print the JSON Schema of task files (for editors)",
             "tooltransfer schema > task.schema.json", _cmd_schema)
    p.add_argument("--out", type=Path, default=None, help="write to this file instead of stdout")
    p = _add(sub, "tools", "draw the tool library (faces, cones) and the Omni's reach",
             "tooltransfer tools --out out/tools.png", _cmd_tools)
    p.add_argument("--out", type=Path, default=DEFAULT_TOOLS_FIGURE, help="output PNG")
    from tooltransfer.planner.apps.batch.commands import add_batch_parser

    add_batch_parser(sub, _add)
    return parser


def _handled_interrupt() -> None:
    """Tell CPython the KeyboardInterrupt was handled: one that ended a nested evaluation (an
    extension's ``PyRun_*`` call) marks the interpreter to exit by SIGINT even when caught, which
    would replace exit code 130 by a signal (3.11; later versions keep the mark elsewhere)."""
    try:
        import ctypes

        ctypes.c_int.in_dll(ctypes.pythonapi, "_Py_UnhandledKeyboardInterrupt").value = 0
    except (ImportError, ValueError, AttributeError, OSError):
        pass


def _interrupted(exc: BaseException) -> bool:
    """A ``KeyboardInterrupt`` behind ``exc`` (a C extension such as CasADi's ``nlpsol`` hit by a Ctrl-C
    returns ``SystemError: ... returned a result with an exception set``, the interrupt as its cause)."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


def main(argv: list[str] | None = None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    import signal
    import traceback

    words = sys.argv[1:] if argv is None else list(argv)
    verbose = "-v" in words or "--verbose" in words  # until the arguments are parsed
    try:
        args = build_parser().parse_args(words)
        verbose = bool(getattr(args, "verbose", False))
        _check_outputs(args)
        quick = argv is None and args.command in QUICK_EXIT
        if quick:
            _fewer_collections()
        code = int(args.func(args))
        sys.stdout.flush()  # here, where a reader that has gone (BrokenPipeError) is handled
        if quick:
            _quick_exit(code)
        return code
    except KeyboardInterrupt:
        if verbose:
            traceback.print_exc()
        print("tooltransfer: interrupted (Ctrl-C)", file=sys.stderr)
        _handled_interrupt()
        return EXIT_INTERRUPTED
    except BrokenPipeError as exc:
        if _stdout_gone():
            return EXIT_BROKEN_PIPE
        return _report(exc, verbose)
    except Exception as exc:  # one line, whatever went wrong (-v: the traceback too)
        return _report(exc, verbose)
    finally:
        if argv is None:  # the console command: a Ctrl-C while the interpreter exits ends it at once, silently
            try:
                signal.signal(signal.SIGINT, signal.SIG_DFL)
            except ValueError:  # not the main thread
                pass


#: Commands that end the process as soon as their work is done (:func:`_quick_exit`): they start no
#: process or thread that outlives them and write their files atomically before returning.
QUICK_EXIT = frozenset({"solve", "export", "schema", "tasks"})


def _fewer_collections() -> None:
    """Run the cyclic garbage collector less often in a quick command: its imports and its planning
    allocate some 10^5 short-lived containers, which the default threshold (700) collects over and
    over (figures in ``benchmarks/README.md``). Every 10,000 allocations keeps what the collector may
    hold back to a few MB, and the process ends with the command."""
    import gc

    gc.set_threshold(10_000, 10, 10)


def _quick_exit(code: int) -> None:
    """End the console command now with ``code``: the exit handlers run (``atexit``: logging's
    flush, a coverage tool's report), the streams are flushed, and the interpreter's teardown of
    every module's objects is skipped (a sizeable share of a quick command, ``benchmarks/README.md``).
    Returns (and the interpreter ends as usual) when a profiler or a debugger is attached, another
    non-daemon thread still runs, or this Python has no ``atexit._run_exitfuncs``."""
    import atexit
    import os
    import threading

    run_exit_handlers = getattr(atexit, "_run_exitfuncs", None)
    others = [t for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    if run_exit_handlers is None or others or sys.getprofile() is not None or sys.gettrace() is not None:
        return
    run_exit_handlers()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _stdout_gone() -> bool:
    """Whether standard output is a pipe (or socket) whose reader has closed it: a write to it fails
    with EPIPE (POLLERR on its end); if so it is pointed at the null device, so that the interpreter's
    last flush at exit does not complain."""
    import os
    import select
    import stat

    try:
        fd = sys.stdout.fileno()
        mode = os.fstat(fd).st_mode
        if not (stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)):
            return False
        poller = select.poll()
        poller.register(fd, select.POLLOUT)
        if not any(ev & select.POLLERR for _, ev in poller.poll(0)):
            return False
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, fd)
        os.close(null)
        return True
    except (OSError, ValueError, AttributeError):  # no usable stdout at all (or no poll on this platform)
        return False


def _report(exc: Exception, verbose: bool) -> int:
    """The one-line message of an exception main() caught (-v: the traceback too); the exit code."""
    import traceback

    from tooltransfer.errors import ToolTransferError

    if _interrupted(exc):  # a Ctrl-C inside a C extension that came back as another error
        print("tooltransfer: interrupted (Ctrl-C)", file=sys.stderr)
        _handled_interrupt()
        return EXIT_INTERRUPTED

    if verbose:
        traceback.print_exc()
    text = _message(exc) if isinstance(exc, ToolTransferError) else (missing_extra(exc) or _unexpected(exc))
    print(f"tooltransfer: error: {text}", file=sys.stderr)
    return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
