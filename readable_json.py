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
import json.encoder
from collections.abc import Callable, Sequence
from typing import Any

_compact = json.JSONEncoder(ensure_ascii=True, allow_nan=True, separators=(", ", ": "))
_strict = json.JSONEncoder(ensure_ascii=True, allow_nan=False, separators=(", ", ": "))


def dumps(doc: Any, *, indent: int = 1, allow_nan: bool = True) -> str:
    """``doc`` as JSON text: objects (and arrays holding an object) one member per line, indented by
    ``indent`` spaces per level; every other value on one line. ``allow_nan=False`` refuses NaN and
    infinities (``ValueError``), as :func:`json.dumps` does."""
    parts: list[str] = []
    one_line, write = _writer(_compact if allow_nan else _strict, indent, parts)
    text = one_line(doc)
    if text is None:
        write(doc, 0)
    else:
        parts.append(text)
    return "".join(parts)


def _c_encoder(enc: json.JSONEncoder) -> Callable[[Any, int], Sequence[str]]:
    """The C encoder ``enc.encode`` makes for every value it is given (``JSONEncoder.iterencode``, one
    shot, no indent), with the same settings, made once (and a fresh table of the containers being
    encoded, for its circular check): the same text without the making, a sizeable share of a
    document of many small arrays. Where Python has no C encoder, ``enc.encode`` itself."""
    make = getattr(json.encoder, "c_make_encoder", None)
    if make is None:
        return lambda value, _level: (enc.encode(value),)
    c_encode: Callable[[Any, int], Sequence[str]] = make(
        {}, enc.default, json.encoder.encode_basestring_ascii, None, enc.key_separator, enc.item_separator,
        enc.sort_keys, enc.skipkeys, enc.allow_nan)
    return c_encode


def _writer(enc: json.JSONEncoder, indent: int, parts: list[str]) -> tuple[Callable[[Any], str | None],
                                                                          Callable[[Any, int], None]]:
    """``one_line(value)``: the text of a value that goes on one line (anything but a non-empty object
    or an array holding one), else None; ``write(value, level)``: append the text of one that does
    not to ``parts``, its members one per line at ``level`` + 1."""
    c_encode = _c_encoder(enc)
    quote = json.encoder.encode_basestring_ascii  # what enc.encode gives for a string (ensure_ascii)
    pads = ["\n"]  # a new line and the indentation of each level
    within: set[int] = set()  # the containers being written (one of them again: a circular reference)

    def pad(level: int) -> str:
        while len(pads) <= level:
            pads.append("\n" + " " * (indent * len(pads)))
        return pads[level]

    def one_line(value: Any) -> str | None:
        if isinstance(value, str):
            return quote(value)
        if isinstance(value, dict):
            if value:
                return None
        elif isinstance(value, list | tuple) and value and isinstance(value[0], dict):
            return None  # an array whose text has a "{" (its first item an object): not encoded twice
        text = "".join(c_encode(value, 0))
        # no "{" in its text: it holds no object (a "{" inside a string only costs a wider layout)
        return None if "{" in text and isinstance(value, list | tuple) else text

    def write(value: Any, level: int) -> None:
        if id(value) in within:
            raise ValueError("Circular reference detected")
        within.add(id(value))
        inner = pad(level + 1)
        sep = inner
        if isinstance(value, dict):
            parts.append("{")
            for key, item in value.items():
                if not isinstance(key, str):  # as json.dumps turns it into a string (1 -> "1", True -> "true")
                    key = next(iter(json.loads("".join(c_encode({key: None}, 0)))))
                text = one_line(item)
                if text is None:
                    parts.append(sep + quote(key) + ": ")
                    write(item, level + 1)
                else:
                    parts.append(sep + quote(key) + ": " + text)
                sep = "," + inner
            parts.append(pad(level) + "}")
        else:
            parts.append("[")
            for item in value:
                text = one_line(item)
                if text is None:
                    parts.append(sep)
                    write(item, level + 1)
                else:
                    parts.append(sep + text)
                sep = "," + inner
            parts.append(pad(level) + "]")
        within.discard(id(value))

    return one_line, write


__all__ = ["dumps"]
