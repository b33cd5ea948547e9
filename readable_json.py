"""JSON text that a person can read and that is quick to write: objects indented, arrays of numbers on one line.

``json.dumps(doc, indent=1)`` puts every number of a plan's sampled arrays on a line of its own (tens of
thousands of lines), and any ``indent`` makes :mod:`json` fall back from its C encoder to the pure-Python
one, several times slower on a plan. :func:`dumps` indents the objects and the arrays that hold objects,
so the structure reads at a glance, and writes every other array (numbers, strings, arrays of arrays of
numbers) in one call of the C encoder on one line. The text parses to the same value as
``json.dumps(doc)``.
"""

from __future__ import annotations

import json
from typing import Any

_compact = json.JSONEncoder(ensure_ascii=True, allow_nan=True, separators=(", ", ": "))
_strict = json.JSONEncoder(ensure_ascii=True, allow_nan=False, separators=(", ", ": "))


def dumps(doc: Any, *, indent: int = 1, allow_nan: bool = True) -> str:
    """``doc`` as JSON text: objects (and arrays holding an object) one member per line, indented by
    ``indent`` spaces per level; every other value on one line. ``allow_nan=False`` refuses NaN and
    infinities (``ValueError``), as :func:`json.dumps` does."""
    parts: list[str] = []
    _write(doc, 0, indent, _compact if allow_nan else _strict, parts)
    return "".join(parts)


def _write(value: Any, level: int, indent: int, enc: json.JSONEncoder, parts: list[str]) -> None:
    if not isinstance(value, dict) or not value:
        text = enc.encode(value)
        # no "{" in its text: it holds no object (a "{" inside a string only costs a wider layout)
        if not isinstance(value, list | tuple) or "{" not in text:
            parts.append(text)
            return
    inner = "\n" + " " * (indent * (level + 1))
    if isinstance(value, dict):
        parts.append("{")
        for i, (key, item) in enumerate(value.items()):
            if not isinstance(key, str):  # as json.dumps turns it into a string (1 -> "1", True -> "true")
                key = next(iter(json.loads(enc.encode({key: None}))))
            parts.append(("," if i else "") + inner + enc.encode(key) + ": ")
            _write(item, level + 1, indent, enc, parts)
        parts.append("\n" + " " * (indent * level) + "}")
        return
    parts.append("[")
    for i, item in enumerate(value):
        parts.append(("," if i else "") + inner)
        _write(item, level + 1, indent, enc, parts)
    parts.append("\n" + " " * (indent * level) + "]")


__all__ = ["dumps"]
