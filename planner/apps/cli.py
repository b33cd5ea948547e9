"""The ``tooltransfer`` command line.

Exit codes: 0 done (solved), 1 infeasible, 2 bad input (a one-line message naming the file and the
field, or the option and the path, never a traceback: ``-v`` adds it for a bug report), 130
stopped by Ctrl-C (one line), 141 when the output's reader has gone (``| head``: silently). Output
paths are checked before any work (a folder where a file is expected, a missing folder, a place
that cannot be written: exit 2 naming the option), and every file is written atomically
(:mod:`tooltransfer.atomic`). Every command has ``--help`` with an example. The console command runs
BLAS on one thread unless the user chose a number (:mod:`tooltransfer.planner.common.blas_threads`).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

# nothing heavy is imported before main() runs: a Ctrl-C while numpy and the rest load is caught too
from tooltransfer.planner.apps import cli_choose, cli_derive, cli_learning, cli_planning
from tooltransfer.planner.common.blas_threads import pin_blas_threads
from tooltransfer.planner.common.command_line import (
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    EXIT_INTERRUPTED,
    check_output,
    missing_extra,
)

#: The tools command's default figure (its folder is made when missing; an explicit path's must exist).
DEFAULT_TOOLS_FIGURE = Path("out/tools.png")


#: Output options by command: (argument name, option as shown, kind; see :func:`check_output`).
OUTPUTS: dict[str, tuple[tuple[str, str, str], ...]] = {
    "solve": (("out", "-o/--out", "file"), ("plot", "--plot", "figure")),
    "learn": (("out", "-o/--out", "file"),),
    "simulate": (("figure", "--figure", "figure"), ("gif", "--gif", "file")),
    "export": (("out", "-o/--out", "file"),),
    "mjcf": (("out", "-o/--out", "file"),),
    "segment": (("figure", "--figure", "figure"),),
    "schema": (("out", "--out", "file"),),
    "tools": (("out", "--out", "figure"),),
    "tools derive": (("tool_out", "-o/--out", "file"), ("plot", "--plot", "figure")),
    "compare": (("out", "--out", "folder"),),
    "choose": (("best", "-o", "file"), ("out", "--out", "folder")),
    "paper": (("out", "--out", "folder"),),
    "demos": (("out", "--out", "folder"),),
    "batch generate": (("out", "--out", "folder"),),
    "batch run": (("db", "--db", "store"),),
    "batch report": (("out", "--out", "folder"),),
}


def _check_outputs(args: argparse.Namespace) -> None:
    command = args.command + (f" {args.batch_command}" if args.command == "batch" else "")
    if args.command == "tools" and getattr(args, "tools_command", None):
        command += f" {args.tools_command}"
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
             "tooltransfer paper --out out", cli_planning.cmd_paper)
    p.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    p = _add(sub, "compare", "solve a task with every variant pair (oe mapping|qp x ss dmp|opt): a metrics table "
             "and one figure; exits 0 when the default pair (qp/opt) is solved, whatever the others give, else 1",
             "tooltransfer compare paper/transfer_tool2 --out out", cli_planning.cmd_compare)
    p.add_argument("task", type=cli_planning.task_file,
                   help="task file (YAML) or a bundled task's name (tooltransfer tasks)")
    p.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    p.add_argument("--json", action="store_true", help="print every plan's status and metrics as JSON")
    p = _add(sub, "demos", "generate demonstrations (or a calibration recording) with the scripted operator on the "
             "simulated Omni", "tooltransfer demos --tool finger --n 8 --seed 0 --out problems/data/finger_demos\n"
             "  tooltransfer demos --calibration --out out/calibration", cli_learning.cmd_demos)
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
             cli_learning.cmd_learn)
    p.add_argument("dataset", type=Path, help="dataset folder (meta.yaml and CSVs)")
    p.add_argument("-o", "--out", type=Path, required=True, help="skills file to write (JSON)")
    p.add_argument("--k", type=float, default=MAPPING_K, help="adjusting factor of the mappings (6)-(7), in (0, 1)")
    p.add_argument("--virtual", choices=choices(VirtualMotion), default=VIRTUAL_MOTION,
                   help="virtual object motion of the SS skill")
    p.add_argument("--calibration", type=Path, default=None,
                   help="identify the push mechanics from this calibration recording (tooltransfer demos "
                   "--calibration) instead of the dataset's pushes")
    cli_learning.add_segment_parser(sub, _add)
    p = _add(sub, "tasks", "list the bundled task files by name (solve and compare take a name or a file)",
             "tooltransfer tasks\n  tooltransfer solve paper/transfer_tool2", cli_planning.cmd_tasks)
    p.add_argument("--paths", action="store_true", help="print each task's file instead of its description")
    p = _add(sub, "solve", "plan a task file: pushes, switches, approach, timing, joints",
             "tooltransfer solve problems/paper/transfer_tool2.yaml -o out/plan.json", cli_planning.cmd_solve)
    p.add_argument("task", type=cli_planning.task_file,
                   help="task file (YAML) or a bundled task's name (tooltransfer tasks)")
    p.add_argument("-o", "--out", type=Path, default=None, help="write the plan (JSON) here")
    p.add_argument("--oe", choices=choices(OEVariant), default=None, help="override the task's OE variant")
    p.add_argument("--ss", choices=choices(SSVariant), default=None, help="override the task's switch variant")
    p.add_argument("--variant", default=None, help="override both as OE/SS, e.g. qp/opt or mapping/dmp")
    p.add_argument("--plot", nargs="?", const=True, default=None,
                   help="draw the plan (Fig. 12; with --simulate also the executions) to PATH (default: next to -o)")
    p.add_argument("--simulate", action="store_true",
                   help="execute the plan on the simulated platform, open loop and closed loop")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--budget", type=float, default=1.0, metavar="K",
                   help="multiply the guided search's expansions and the certificate's block updates by K >= 1 "
                        "(for a task left unknown)")
    p = _add(sub, "simulate", "execute a plan file on the simulated platform (open loop, and closed loop on request)",
             "tooltransfer simulate out/plan.json --closed-loop --figure out/fig12.png --gif out/run.gif",
             cli_planning.cmd_simulate)
    p.add_argument("plan", type=Path, help="plan file (JSON)")
    p.add_argument("--closed-loop", action="store_true",
                   help="also execute closed loop (re-plan the corners from the observed puck)")
    p.add_argument("--figure", type=Path, default=None, help="write planned versus executed paths (Fig. 12) here")
    p.add_argument("--gif", type=Path, default=None, help="write an animated GIF of the (last) execution here")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.add_argument("--force", action="store_true", help="run a plan that fails its checks against itself and its "
                   "task (or a violated plan) anyway, with a warning")
    _add_mujoco_tools(sub, p)
    p = _add(sub, "export", "write a plan's joint trajectory (positions, velocities, accelerations) for a real arm: "
             "CSV, NumPy .npz or a ROS JointTrajectory as JSON",
             "tooltransfer export out/plan.json --format joint-trajectory -o out/plan.trajectory.json",
             cli_planning.cmd_export)
    p.add_argument("plan", type=Path, help="plan file (JSON)")
    p.add_argument("--format", choices=("csv", "npz", "joint-trajectory"), required=True, help="what to write")
    p.add_argument("-o", "--out", type=Path, default=None,
                   help="file to write (default: the plan's name ending .csv, .npz or .trajectory.json)")
    p.add_argument("--joint-names", default=None, help="the joints' names for the robot, comma-separated "
                   "(default: the plan's, q1,q2,q3)")
    p.add_argument("--force", action="store_true", help="export a plan that fails its checks against itself and "
                   "its task (or a violated plan) anyway, with a warning")
    cli_planning.add_view_parser(sub, _add)
    p = _add(sub, "schema", "print the JSON Schema of task files (for editors)",
             "tooltransfer schema > task.schema.json", cli_planning.cmd_schema)
    p.add_argument("--out", type=Path, default=None, help="write to this file instead of stdout")
    p = _add(sub, "tools", "draw the tool library (faces, cones) and the Omni's reach",
             "tooltransfer tools --out out/tools.png", cli_planning.cmd_tools)
    p.add_argument("--out", type=Path, default=DEFAULT_TOOLS_FIGURE, help="output PNG")
    cli_derive.add_derive_parser(p, _add)
    cli_choose.add_choose_parser(sub, _add, cli_planning.task_file)
    from tooltransfer.planner.apps.batch.commands import add_batch_parser

    add_batch_parser(sub, _add)
    return parser


def _add_mujoco_tools(sub: argparse._SubParsersAction, simulate: argparse.ArgumentParser) -> None:
    """``simulate --viewer`` and the ``mjcf`` command: MuJoCo's own tools on the simulated scene."""
    simulate.add_argument("--viewer", action="store_true", help="then replay the plan in MuJoCo's viewer, in real "
                          "time (needs a display; on macOS run under mjpython)")
    p = _add(sub, "mjcf", "write the MuJoCo scene (MJCF) of a task or a plan: the Omni with the tool, the puck, the "
             "obstacles, the target, and a keyframe 'start'", "tooltransfer mjcf paper/transfer_tool2 -o scene.xml\n"
             "  tooltransfer mjcf out/plan.json -o scene.xml\n  python -m mujoco.viewer --mjcf=scene.xml",
             cli_planning.cmd_mjcf)
    p.add_argument("source", help="task file (YAML), a bundled task's name, or a plan file (.json)")
    p.add_argument("-o", "--out", type=Path, required=True, help="MJCF file to write")


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

    if argv is None:  # the console command: one BLAS thread unless the user chose (before NumPy loads)
        pin_blas_threads()
    words = sys.argv[1:] if argv is None else list(argv)
    verbose = "-v" in words or "--verbose" in words  # until the arguments are parsed
    try:
        args = build_parser().parse_args(words)
        verbose = bool(getattr(args, "verbose", False))
        _check_outputs(args)
        quick = argv is None and args.command in QUICK_EXIT
        if quick:
            _fewer_collections(args.command)
        code = int(args.func(args))
        sys.stdout.flush()  # here, where a reader that has gone (BrokenPipeError) is handled
        if quick:
            _quick_exit(code)
        return code
    except KeyboardInterrupt:
        if verbose:
            import traceback  # here: a command that succeeds does not need it

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
QUICK_EXIT = frozenset({"solve", "export", "view", "schema", "tasks"})


#: The quick commands that run without the cyclic garbage collector (:func:`_fewer_collections`): one
#: plan file read, one file written, objects that reference counting frees; the cycles their imports
#: leave are about a thousand objects (0.2 MB of peak memory on the transfer plan), while the
#: collector's passes over the imported modules' objects took 13-20 ms of ``export``'s 0.5 s.
WITHOUT_CYCLE_COLLECTOR = frozenset({"export", "view"})


def _fewer_collections(command: str) -> None:
    """Run the cyclic garbage collector less often in a quick command: its imports and its planning
    allocate some 10^5 short-lived containers, which the default threshold (700) collects over and
    over (figures in ``benchmarks/README.md``). Every 10,000 allocations keeps what the collector may
    hold back to a few MB, and the process ends with the command; the commands of
    :data:`WITHOUT_CYCLE_COLLECTOR` run without it."""
    import gc

    if command in WITHOUT_CYCLE_COLLECTOR:
        gc.disable()
    else:
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
