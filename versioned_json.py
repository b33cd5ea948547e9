"""Versioned JSON files: one way for every skill format to write and read itself.

A versioned document is a JSON object whose ``"format"`` field names its format and version,
``"<name>/<version>"`` (``tooltransfer.dmp/1``, ``tooltransfer.ss/1``, ``tooltransfer.oe/1``,
``tooltransfer.skills/1``, ``tooltransfer.mechanics/1``); the rest of the object belongs to the format.

* :func:`write_versioned` writes one atomically (:mod:`tooltransfer.atomic`: a temporary file beside
  the target, flushed to disk, replaces it in one step), so no half-written skill file is ever left;
* :func:`read_json` parses a file, :func:`check_format` checks a document's format and version,
  :func:`read_versioned` does both; a missing file, invalid JSON, another format or another version
  raises :class:`~tooltransfer.errors.SkillFileError` naming the file (the field, for a document
  nested in another).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from tooltransfer.atomic import write_text
from tooltransfer.errors import SkillFileError
from tooltransfer.readable_json import dumps


def format_tag(name: str, version: int) -> str:
    """The ``"format"`` value of format ``name`` at ``version``: ``"<name>/<version>"``."""
    return f"{name}/{version}"


def check_format(doc: Any, name: str, version: int, source: str = "<dict>") -> dict[str, Any]:
    """``doc`` itself when it is a JSON object of format ``name`` at ``version``; otherwise raise
    :class:`SkillFileError` naming ``source`` and the expected ``"<name>/<version>"``."""
    tag = format_tag(name, version)
    if not isinstance(doc, dict) or "format" not in doc:
        got = "an object without a 'format' field" if isinstance(doc, dict) else f"a JSON {type(doc).__name__}"
        raise SkillFileError(source, f"not a tooltransfer skill file: expected format {tag!r}, got {got}")
    fmt = str(doc["format"])
    got_name, _, got_version = fmt.partition("/")
    if not re.fullmatch(r"[A-Za-z0-9_.-]{1,60}/[0-9]{1,6}", fmt):  # not a format tag: the file's text is not echoed
        raise SkillFileError(source, f"expected format {tag!r}, got a 'format' field that is no format tag")
    if got_name != name:
        raise SkillFileError(source, f"expected format {tag!r}, got {fmt!r}")
    if got_version != str(version):
        raise SkillFileError(
            source, f"format version {got_version!r} of {name!r} is not supported (this library reads {tag!r})"
        )
    return doc


#: Largest skill or cache file read [bytes] (a skills file is about 200 kB).
MAX_JSON_BYTES = 64 * 2**20


def read_json(path: str | Path) -> Any:
    """Parsed JSON of a file (a regular file of at most :data:`MAX_JSON_BYTES`, read without blocking:
    :func:`tooltransfer.regular_file.read_regular`); a missing, special, oversized or unreadable file,
    or invalid JSON, raises :class:`SkillFileError` naming the file (quoting none of it)."""
    from tooltransfer.regular_file import read_regular

    p = Path(path)

    def refuse(source: str, where: str, expected: str, got: object) -> SkillFileError:
        if got == "No such file or directory":
            return SkillFileError(source, "file not found")
        return SkillFileError(source, f"expected {expected}, got {got}")

    data = read_regular(p, refuse, "JSON file", MAX_JSON_BYTES)
    try:
        return json.loads(data.decode("utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        why = f"line {exc.lineno}, column {exc.colno}: {exc.msg}" if isinstance(exc, json.JSONDecodeError) else \
            f"a byte that is not UTF-8 at offset {exc.start}"
        raise SkillFileError(str(p), f"not valid JSON ({why})") from None


def read_versioned(path: str | Path, name: str, version: int) -> dict[str, Any]:
    """The JSON object in ``path``, checked to be of format ``name`` at ``version`` (:func:`check_format`)."""
    return check_format(read_json(path), name, version, str(path))


def write_versioned(path: str | Path, doc: dict[str, Any], *, indent: int | None = None, allow_nan: bool = True,
                    mkdir: bool = False) -> Path:
    """Write the versioned document ``doc`` (it carries its ``"format"``) to ``path`` as JSON
    (``indent``: objects indented by that many spaces per level and arrays of numbers on one line,
    :func:`tooltransfer.readable_json.dumps`; None: one line; ``allow_nan=False`` refuses NaN and
    infinities), atomically
    (:func:`tooltransfer.atomic.write_text`; ``mkdir``: the parent folders are made first); returns the
    path. An error while writing (a full disk) leaves ``path`` as it was and names it."""
    if not isinstance(doc.get("format"), str) or "/" not in doc["format"]:
        raise ValueError(f"a versioned document needs a 'format' field '<name>/<version>', got {doc.get('format')!r}")
    text = json.dumps(doc, allow_nan=allow_nan) if indent is None else dumps(doc, indent=indent, allow_nan=allow_nan)
    return write_text(path, text, mkdir=mkdir)


__all__ = ["check_format", "format_tag", "read_json", "read_versioned", "write_versioned"]
