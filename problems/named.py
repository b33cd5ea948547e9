"""Task files bundled with the package, addressable by name after a normal install.

A name is ``<folder>/<stem>`` of a task file in ``problems/paper`` (the paper's cases) or
``problems/hard`` (cases at the edges: out of reach, behind an obstacle, infeasible by design), e.g.
``paper/transfer_tool2``: ``tooltransfer solve paper/transfer_tool2``; ``tooltransfer tasks`` lists them.
Each states the verdict ``solve`` gives it in a comment, ``# ... Expected: solved``
(:func:`stated_outcome`), which its test checks.
"""

from __future__ import annotations

import re
from pathlib import Path

#: The folders of bundled task files, in listing order.
FOLDERS = ("paper", "hard")
#: The verdicts a task file may state (those of ``solve``).
VERDICTS = ("solved", "infeasible", "unknown")
_HERE = Path(__file__).resolve().parent
_STATED = re.compile(r"^#.*\bExpected: (\w+)", re.MULTILINE)


def bundled_tasks() -> dict[str, Path]:
    """Every bundled task file by name (``"paper/transfer_tool2"`` -> its path), sorted by name."""
    return {f"{folder}/{p.stem}": p for folder in FOLDERS for p in sorted((_HERE / folder).glob("*.yaml"))}


def task_file(name_or_path: str | Path) -> Path:
    """The task file ``name_or_path`` means: an existing file as given, else a bundled task of that name
    (with or without ``.yaml``), else the path as given (reading it then says that it is missing)."""
    path = Path(name_or_path)
    if path.exists():
        return path
    name = str(name_or_path).removesuffix(".yaml").removesuffix(".yml")
    return bundled_tasks().get(name, path)


def stated_outcome(path: Path) -> str | None:
    """The verdict a task file states in its comments (``# Expected: infeasible (certified ...)``
    gives ``"infeasible"``), or None where it states none or more than one."""
    found = _STATED.findall(path.read_text(encoding="utf-8"))
    return found[0] if len(found) == 1 and found[0] in VERDICTS else None
