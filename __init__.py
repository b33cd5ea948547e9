"""tooltransfer: learn pushing skills (DMPs) from demonstrations with one tool, plan with a new one.

The repository's root is this package (``pyproject.toml`` maps it): its folders are the
subpackages ``tooltransfer.dmp`` (the DMP core), ``tooltransfer.tools`` (tools, the object, the
Omni, the simulated platform, the push mechanics), ``tooltransfer.problems`` (task files and
datasets) and ``tooltransfer.planner`` (skills, planning, plans, execution, the CLI, batch runs).

What a user needs first is here::

    import tooltransfer as tt

    task = tt.load_task("paper/transfer_tool2")  # a bundled task by name, or a task file's path
    plan = tt.solve(task)  # a tt.Plan; plan.status is "solved" only when every hard check holds
    plan.write("plan.json")
    same = tt.read_plan("plan.json")
    choice = tt.choose_tool(task, ["finger", "slope"])  # each tool planned and executed, ranked
    best = choice.best  # the best candidate (its tool, plan, executions), None when no tool solves it

``tt.batch`` is the batch package (``tt.batch.load(db)``: a batch's results as a pandas DataFrame,
with the ``data`` extra). The names are imported on first use, so ``import tooltransfer`` (and every
``tooltransfer`` command) stays light.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from tooltransfer.dmp.primitive import DMP
    from tooltransfer.errors import InfeasibleError, InputError, ToolTransferError
    from tooltransfer.planner.apps import batch
    from tooltransfer.planner.apps.choose.run import Choice, choose_tool
    from tooltransfer.planner.planning.plan import Plan, read_plan
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import Task, load_task

__all__ = [
    "DMP",
    "Choice",
    "InfeasibleError",
    "InputError",
    "Plan",
    "Task",
    "ToolTransferError",
    "__version__",
    "batch",
    "choose_tool",
    "load_task",
    "read_plan",
    "solve",
]

#: Where each public name lives (imported when first asked for).
_HOMES = {
    "DMP": "tooltransfer.dmp.primitive",
    "Choice": "tooltransfer.planner.apps.choose.run",
    "choose_tool": "tooltransfer.planner.apps.choose.run",
    "InfeasibleError": "tooltransfer.errors",
    "InputError": "tooltransfer.errors",
    "ToolTransferError": "tooltransfer.errors",
    "Plan": "tooltransfer.planner.planning.plan",
    "read_plan": "tooltransfer.planner.planning.plan",
    "solve": "tooltransfer.planner.planning.solve",
    "Task": "tooltransfer.problems.task",
    "load_task": "tooltransfer.problems.task",
}


def _version() -> str:
    """The installed distribution's version (``pyproject.toml`` is its one source)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("tooltransfer")
    except PackageNotFoundError:  # the sources on sys.path without an install
        return "0+unknown"


#: Subpackages reached by a short name (``tt.batch.load(db)``), imported when first asked for.
_MODULES = {"batch": "tooltransfer.planner.apps.batch"}


def __getattr__(name: str) -> Any:
    value: Any
    if name == "__version__":
        value = _version()
    elif name in _MODULES:
        value = import_module(_MODULES[name])
    elif name in _HOMES:
        value = getattr(import_module(_HOMES[name]), name)
    else:
        raise AttributeError(f"module 'tooltransfer' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
