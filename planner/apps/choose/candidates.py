"""The candidates of a tool choice: one task per tool, the given task with its tool replaced.

A candidate is named by a library tool's name (``slope``) or a tool file's path (``my/rake.yaml``,
anything with a ``/`` or a ``.yaml``/``.yml`` ending): a library tool goes into the task by name, a
tool file as the task's inline tool (its fields as the file has them), so whatever a tool file may
hold (faces, or an outline alone whose faces the loader derives) plans the same way it loads.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tooltransfer.errors import InputError, ToolTransferError
from tooltransfer.problems.task import Task, task_from_dict


@dataclass(frozen=True)
class Candidate:
    """One tool to try.

    Attributes:
        label: how the user named it (a library name or the path as given).
        tool: the tool's own name (its file's ``name``).
        task: the task with this tool.
    """

    label: str
    tool: str
    task: Task


def is_path(text: str) -> bool:
    """Whether a tool argument names a file rather than a library tool."""
    return "/" in text or "\\" in text or text.endswith((".yaml", ".yml"))


def _tool_file(text: str, field: str) -> dict[str, Any]:
    """The parsed fields of the tool file ``text``, checked by the tool loader first (its faces derived
    or read): an error names ``field``, the file and what was wrong."""
    from tooltransfer.tools.library import load_tool
    from tooltransfer.yaml_file import read_yaml

    p = Path(text)
    if not p.is_file():
        raise InputError(field, "a library tool name or an existing tool file (YAML)",
                         f"{text!r}: " + ("a folder" if p.is_dir() else "no such file"))
    try:
        load_tool(p)
    except ToolTransferError as exc:
        raise InputError(field, f"a valid tool file ({exc})", text) from None

    def error(source: str, where: str, expected: str, got: object) -> InputError:
        return InputError(f"{field} {source}: {where}", expected, got)

    data = read_yaml(p, error, "tool file")
    if not isinstance(data, dict):
        raise InputError(field, "a tool file holding a mapping of the tool's fields", text)
    return data


def tool_arguments(text: str, field: str = "--tools") -> list[str]:
    """A comma-separated list of tools, each checked to be a library name or a file (``field`` names
    the argument in errors); duplicates dropped, the order kept."""
    from tooltransfer.tools.library import library_names

    names = [t.strip() for t in text.split(",")]
    if not text.strip() or any(not t for t in names):
        raise InputError(field, "library tool names or tool files, comma-separated, none empty", text)
    library = library_names()
    for t in names:
        if not is_path(t) and t not in library:
            raise InputError(field, f"library tool names ({', '.join(library)}) or tool files (YAML paths)", t)
    return list(dict.fromkeys(names))


def candidates(task: Task, tools: Sequence[str | Path] | None = None, field: str = "--tools") -> list[Candidate]:
    """One candidate per tool of ``tools`` (library names and tool-file paths; None: every library tool),
    each the task with that tool and the task's own file as its origin (relative skills paths stay
    valid).

    Raises:
        InputError: naming ``field``: an unknown name, a missing or invalid file, an empty list, or a
            tool with which the task is not valid (its search too large for the tool's faces).
    """
    from tooltransfer.tools.library import library_names

    names = list(library_names()) if tools is None else tool_arguments(",".join(str(t) for t in tools), field)
    if not names:
        raise InputError(field, "at least one tool", "none")
    base = json.loads(task.model_dump_json())
    source = task.source or "<task>"
    out = []
    for name in names:
        tool: str | dict[str, Any] = _tool_file(name, field) if is_path(name) else name
        try:
            t = task_from_dict({**base, "tool": tool}, source)
        except InputError as exc:
            raise InputError(field, f"a tool the task is valid with ({exc})", name) from None
        t._source = task.source
        out.append(Candidate(name, tool["name"] if isinstance(tool, dict) else name, t))
    labels = [c.label for c in out]
    if len(set(labels)) != len(labels):  # pragma: no cover - tool_arguments drops duplicates
        raise InputError(field, "each tool once", ",".join(labels))
    return out
