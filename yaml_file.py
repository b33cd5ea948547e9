"""Reading a YAML (or JSON) file for the project's file formats (task files, dataset ``meta.yaml`` and
``truth.yaml``, batch files), with errors that name the file and, where it applies, the line and
column; hostile input is refused the same way, never with a traceback:

* the file: a regular file (a FIFO, a device or a folder is refused by its kind, and nothing blocks:
  :mod:`tooltransfer.regular_file`);
* the bytes: at most :data:`MAX_BYTES`, UTF-8 text (a UTF-8 byte-order mark is skipped; UTF-16 or
  UTF-32, Latin-1 and binary files are named as such);
* the structure: at most :data:`MAX_DEPTH` nested collections (``[[[[...`` would exhaust Python's
  recursion), no key twice in one mapping (naming the key and both lines: YAML readers usually keep
  the last one silently), aliases that add at most :data:`MAX_ALIAS_EXPANSION` values when expanded
  (an alias-expansion "billion laughs" bomb is a few lines of text);
* numbers: ``1e-3``, ``5E+2`` and ``+1e3`` (YAML 1.2 and JSON floats, which YAML 1.1 reads as strings)
  are floats, as users write them every day.

:func:`clip` shortens a value echoed in a message (at most :data:`ECHO_CHARS` characters).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode

from tooltransfer.errors import ToolTransferError

#: Largest file read [bytes]: the project's YAML files are a few kB (a generated ``truth.yaml`` of 8
#: demonstrations 10 kB); reading 1 MB of YAML takes about a second.
MAX_BYTES = 2**20
#: Deepest nesting of collections (task files nest 4 deep).
MAX_DEPTH = 64
#: Most values aliases may add when expanded (``*anchor`` repeats its anchor's whole subtree).
MAX_ALIAS_EXPANSION = 10_000
#: Longest value echoed in an error message [characters].
ECHO_CHARS = 100

Error = Callable[[str, str, str, object], Exception]

# YAML 1.2 / JSON floats that YAML 1.1's resolver leaves as strings: an exponent without a dot or
# without a sign (1e-3, 1E3, 2.5e3); YAML 1.1's own forms (0.005, 1.0e+3, .inf) resolve as before
_FLOAT_12 = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$")


def clip(value: object, limit: int = ECHO_CHARS) -> str:
    """``value`` as text for a message: at most ``limit`` characters on one line (longer text is cut,
    saying how long it was)."""
    text = value if isinstance(value, str) else repr(value)
    text = text.replace("\r", "\\r").replace("\n", "\\n")
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text)} characters)"


class _RefusedYAML(yaml.YAMLError, ToolTransferError):
    """A document this reader refuses (depth, duplicate key, alias bomb), with the node's mark."""

    def __init__(self, problem: str, mark: yaml.Mark | None) -> None:
        super().__init__(problem)
        self.problem = problem
        self.problem_mark = mark


class _PyLoader(yaml.SafeLoader):
    """PyYAML's pure-Python safe loader, its composer's recursion bounded (used without libyaml)."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent: Node | None, index: object) -> Node:  # type: ignore[override]
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise _RefusedYAML(f"at most {MAX_DEPTH} nested collections", self.peek_event().start_mark)
            return super().compose_node(parent, index)  # type: ignore[arg-type]
        finally:
            self._depth -= 1


class _CLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """libyaml's safe loader: it parses and composes in C (several times faster; its own nesting
    bound is 1000 levels), :func:`_check` bounds the rest."""


_Loader: type = _CLoader if hasattr(yaml, "CSafeLoader") else _PyLoader
for _cls in (_CLoader, _PyLoader):
    _cls.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_12, list("-+0123456789."))


def _check(root: Node) -> None:
    """Refuse a composed document (module docstring): nesting deeper than :data:`MAX_DEPTH` (as
    written or once aliases are expanded), a key twice in one mapping, aliases that add more than
    :data:`MAX_ALIAS_EXPANSION` values, an alias inside its own anchor. One iterative pass over the
    nodes, nothing expanded."""
    size: dict[int, int] = {}  # node -> its number of nodes once aliases are expanded
    height: dict[int, int] = {}
    open_: set[int] = set()
    stack: list[tuple[Node, int, bool]] = [(root, 1, False)]
    while stack:
        node, depth, done = stack.pop()
        key = id(node)
        if isinstance(node, ScalarNode):
            size[key], height[key] = 1, 0
            continue
        children = [c for kv in node.value for c in kv] if isinstance(node, MappingNode) else list(node.value)
        if done:
            size[key] = 1 + sum(size[id(c)] for c in children)
            height[key] = 1 + max((height[id(c)] for c in children), default=0)
            open_.discard(key)
            if height[key] > MAX_DEPTH:
                raise _RefusedYAML(f"at most {MAX_DEPTH} nested collections (aliases included)", node.start_mark)
            continue
        if key in size:
            continue
        if key in open_:
            raise _RefusedYAML("no alias inside its own anchor (a recursive structure)", node.start_mark)
        if depth > MAX_DEPTH:
            raise _RefusedYAML(f"at most {MAX_DEPTH} nested collections", node.start_mark)
        if isinstance(node, MappingNode):
            seen: dict[tuple[str, str], yaml.Mark] = {}
            for key_node, _ in node.value:  # the keys as written (merge keys are expanded later)
                if not isinstance(key_node, ScalarNode) or key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                first = seen.setdefault((key_node.tag, key_node.value), key_node.start_mark)
                if first is not key_node.start_mark:
                    raise _RefusedYAML(f"each key once in a mapping, but {clip(key_node.value)!r} is given again "
                                       f"(first on line {first.line + 1})", key_node.start_mark)
        open_.add(key)
        stack.append((node, depth, True))
        stack.extend((c, depth + 1, False) for c in children)
    added = size[id(root)] - len(size)
    if added > MAX_ALIAS_EXPANSION:
        raise _RefusedYAML(f"aliases that add at most {MAX_ALIAS_EXPANSION} values when expanded, not {added} (an "
                           "alias-expansion bomb?)", None)


_CONTROL = bytes(range(0, 9)) + bytes(range(14, 32))


def _decode(data: bytes) -> tuple[str | None, str]:
    """``(text, "")`` for UTF-8 (a byte-order mark skipped), else ``(None, what the bytes are)``."""
    for bom, name in ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"), (b"\xff\xfe", "UTF-16"),
                      (b"\xfe\xff", "UTF-16")):
        if data.startswith(bom):
            return None, f"a {name} file (save it as UTF-8)"
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    head = data[:4096]
    zeros = (head[0::2].count(0), head[1::2].count(0))  # ASCII as UTF-16: every other byte is zero
    if len(head) >= 8 and max(zeros) > len(head) // 4 and min(zeros) < len(head) // 16:
        return None, "a UTF-16 file without a byte-order mark (save it as UTF-8)"
    try:
        return data.decode("utf-8"), ""
    except UnicodeDecodeError as exc:
        if sum(head.count(c) for c in _CONTROL) > len(head) // 20:
            return None, "a binary file"
        line = data[: exc.start].count(b"\n") + 1
        return None, (f"a byte that is not UTF-8 (0x{data[exc.start]:02x} on line {line}: a Latin-1 or other 8-bit "
                      "file? save it as UTF-8)")


def read_text(path: str | Path, error: Error, what: str, max_bytes: int = MAX_BYTES, *,
              inside: str | Path | None = None) -> str:
    """The UTF-8 text of ``path`` (at most ``max_bytes``; a regular file, never blocking, inside the
    folder ``inside`` when given: :func:`tooltransfer.regular_file.read_regular`); anything else raises
    ``error(path, "<file>", expected, got)`` naming the file and what it holds instead."""
    from tooltransfer.regular_file import read_regular

    p = Path(path)
    data = read_regular(p, error, what, max_bytes, inside=inside)
    text, why = _decode(data)
    if text is None:
        raise error(str(p), "<file>", f"a {what} in UTF-8 text", why)
    return text


def parse_yaml(text: str, source: str, error: Error) -> Any:
    """The contents of the YAML ``text`` (module docstring); refused or invalid YAML raises
    ``error(source, where, expected, got)`` with ``where`` ``line L, column C`` where known."""
    def unprintable(exc: yaml.reader.ReaderError) -> Exception:  # NUL and other control characters
        pos = exc.position if isinstance(exc.position, int) else 0
        line, col = text.count("\n", 0, pos) + 1, pos - (text.rfind("\n", 0, pos) + 1) + 1
        char = exc.character if isinstance(exc.character, int) else ord(exc.character or "\0")
        return error(source, f"line {line}, column {col}", "printable text (YAML allows no control characters)",
                     f"the character #x{char:04x}")

    try:
        loader = _Loader(text)
    except yaml.reader.ReaderError as exc:
        raise unprintable(exc) from None
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check(node)
        return loader.construct_document(node)
    except yaml.reader.ReaderError as exc:
        raise unprintable(exc) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "<file>"
        expected = "valid YAML"
        problem = getattr(exc, "problem", None) or str(exc)
        if isinstance(exc, _RefusedYAML):
            expected, problem = problem, None
        elif "nesting depth" in str(problem):  # libyaml's own bound (1000 levels)
            expected, problem = f"at most {MAX_DEPTH} nested collections", "deeper nesting"
        raise error(source, where, expected, clip(problem) if problem else None) from None
    except (ValueError, TypeError, OverflowError) as exc:  # a scalar its constructor refuses (2024-13-45, 5000 digits)
        raise error(source, "<file>", "valid YAML values", clip(str(exc))) from None
    except RecursionError:  # a structure deeper than MAX_DEPTH allows for already (a guard)
        raise error(source, "<file>", f"at most {MAX_DEPTH} nested collections", "deeper nesting") from None
    finally:
        loader.dispose()


def read_yaml(path: str | Path, error: Error, what: str, max_bytes: int = MAX_BYTES, *,
              inside: str | Path | None = None) -> Any:
    """The parsed contents of ``path`` (module docstring); an unreadable, oversized, non-regular or
    non-UTF-8 file, one outside the folder ``inside`` (when given), invalid YAML or refused YAML raises
    ``error(path, where, expected, got)`` (``where`` is ``<file>`` or ``line L, column C``); ``what``
    names the file kind in the message (e.g. ``"task file"``)."""
    return parse_yaml(read_text(path, error, what, max_bytes, inside=inside), str(path), error)


__all__ = ["ECHO_CHARS", "MAX_ALIAS_EXPANSION", "MAX_BYTES", "MAX_DEPTH", "clip", "parse_yaml", "read_text",
           "read_yaml"]
