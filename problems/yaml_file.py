"""Reading a YAML (or JSON) file for the project's file formats, with errors that name the file and,
for a syntax error, the line and column."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml


def read_yaml(path: str | Path, error: Callable[[str, str, str, object], Exception], what: str) -> Any:
    """The parsed contents of ``path``; an unreadable file or invalid YAML raises
    ``error(path, where, expected, got)`` (``where`` is ``<file>`` or ``line L, column C``);
    ``what`` names the file kind in the message (e.g. ``"task file"``)."""
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise error(str(p), "<file>", f"a readable {what}", exc.strerror) from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "<file>"
        raise error(str(p), where, "valid YAML", getattr(exc, "problem", str(exc))) from None
