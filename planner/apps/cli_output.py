"""What the command line's commands share: a progress display, a summary table with units, a
figure written through a temporary path, a safe file-name stem from a task's name.

It imports nothing heavy at module level (the command line catches a Ctrl-C while numpy and the rest load).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def spinner(text: str, quiet: bool = False) -> object:
    """A progress display for a step that takes more than a second (nothing when ``quiet``)."""
    import contextlib

    if quiet:
        return contextlib.nullcontext()
    from rich.console import Console

    return Console(stderr=True).status(text)


def print_summary(summary: dict[str, object], title: str) -> None:
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


@contextmanager
def written(path: Path) -> Iterator[Path]:
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
