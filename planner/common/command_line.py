"""What the commands of the command line share (:mod:`tooltransfer.planner.apps.cli` and the commands
it runs from other modules, such as :func:`tooltransfer.planner.execution.export.run_export`): the exit codes and
the check of an output path before any work is done.

It imports nothing heavy (the command line catches a Ctrl-C while numpy and the rest load).
"""

from __future__ import annotations

import os
from pathlib import Path

EXIT_OK, EXIT_INFEASIBLE, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130
EXIT_UNKNOWN = 3
"""``solve``: no plan and no certificate (the verdict ``unknown``; ``EXIT_INFEASIBLE`` is a certified
``infeasible``, ``EXIT_OK`` a ``solved`` plan)."""
EXIT_NOT_REACHED = 4
"""``simulate --closed-loop``: the closed loop ended without reaching the target (its status is not
``reached``: the summary says which and why)."""
VERDICT_EXIT = {"solved": EXIT_OK, "infeasible": EXIT_INFEASIBLE, "unknown": EXIT_UNKNOWN}
"""The exit code of each verdict (:attr:`tooltransfer.planner.planning.plan.Plan.verdict`)."""
EXIT_BROKEN_PIPE = 141
"""The reader of the output went away (``tooltransfer tasks | head``): 128 + SIGPIPE, as a shell reports a
command the signal ended; nothing is printed."""


def _nearest_existing(path: Path) -> Path:
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def _writable(folder: Path) -> str:
    """Why nothing can be created in ``folder`` ("" if something can): it is tried."""
    probe = folder / f".tooltransfer-probe-{os.getpid()}"
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
    except FileExistsError:
        return ""
    except OSError as exc:
        return exc.strerror or str(exc)
    try:
        probe.unlink()
    except OSError:
        pass
    return ""


#: The file name endings a figure may have (the formats matplotlib writes without further packages).
FIGURE_SUFFIXES = (".png", ".svg", ".pdf", ".jpg", ".jpeg", ".eps", ".ps", ".tif", ".tiff", ".webp")


def check_output(option: str, path: Path, kind: str = "file", *, make_folders: bool = False) -> None:
    """Check an output path before any work is done; raise :class:`~tooltransfer.errors.InputError` naming
    ``option`` and ``path``. ``kind``: ``"file"`` (its folder must exist, unless ``make_folders``),
    ``"figure"`` (a file whose name ends in one of :data:`FIGURE_SUFFIXES`: the format is taken from it),
    ``"folder"`` (made with its parents when missing)."""
    from tooltransfer.errors import InputError

    path = Path(path)
    if kind == "figure":
        if path.suffix.lower() not in FIGURE_SUFFIXES:
            raise InputError(option, f"a figure file name ending in {', '.join(FIGURE_SUFFIXES)}", str(path))
        kind = "file"
    if len(os.fsencode(str(path))) > 4000 or any(len(os.fsencode(part)) > 255 for part in path.parts):
        raise InputError(option, "a path whose names have at most 255 bytes", f"{str(path)[:100]}...")
    if kind == "folder":
        if path.exists() and not path.is_dir():
            raise InputError(option, "a folder (to write into)", f"{path}, which is a file")
        base = _nearest_existing(path)
        if not base.is_dir():
            raise InputError(option, "a folder that can be made", f"{path} ({base} is a file)")
        why = _writable(base)
        if why:
            raise InputError(option, "a folder that can be written", f"{path} ({base}: {why})")
        return
    if path.is_dir():
        raise InputError(option, "a file path, not a folder", str(path))
    parent = path.parent
    if not parent.exists():
        if not make_folders:
            raise InputError(option, "a file in an existing folder", f"{path} (there is no folder {parent})")
        parent = _nearest_existing(parent)
    if not parent.is_dir():
        raise InputError(option, "a file in a folder", f"{path} ({parent} is not a folder)")
    why = _writable(parent)
    if why:
        raise InputError(option, "a file in a place that can be written", f"{path} ({parent}: {why})")


#: Optional dependencies by their import name -> the extra that installs them (``pyproject.toml``).
EXTRAS = {"mujoco": "sim", "matplotlib": "plots", "PIL": "plots", "dask": "dask", "distributed": "dask",
          "bokeh": "report", "plotly": "report", "pandas": "data"}


def missing_extra(exc: BaseException) -> str | None:
    """For an import of an optional dependency that failed, the one line that says what to install
    (None for any other error): the core (planning, plans, export, learning) needs none of them."""
    if not isinstance(exc, ModuleNotFoundError) or not exc.name:
        return None
    top = exc.name.split(".")[0]
    extra = EXTRAS.get(top)
    if extra is None:
        return None
    return f"this command needs {top}, which is optional: pip install 'tooltransfer[{extra}]' (or [all])"
