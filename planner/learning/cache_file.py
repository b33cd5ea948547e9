"""A file of the skills cache (:func:`tooltransfer.planner.learning.skills.cache_dir`): what was learned
from a dataset, with a checksum of it and of what it was learned from.

Format ``tooltransfer.cache/1``::

    {"format": "tooltransfer.cache/1", "source_sha256": "<hash of the dataset learned from>",
     "sha256": "<SHA-256 of the source hash and the payload's JSON>", "payload": <the learned object>}

Why: a cache file is read instead of learning again, so a file edited to other valid values (a
friction coefficient changed by hand, a file copied from another dataset under this one's name)
would be used silently. :func:`read_cache` gives the payload only when the checksum matches the
payload and the source it is asked for; anything else (a damaged or edited file, another source, a
file of an older cache format) reads as missing, and the caller learns again and overwrites it.
The checksum guards against edits and mix-ups, not against someone who recomputes it: the cache
folder is the user's own.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from tooltransfer.errors import SkillFileError
from tooltransfer.versioned_json import check_format, format_tag, read_json, write_versioned

CACHE_NAME, CACHE_VERSION = "tooltransfer.cache", 1
CACHE_FORMAT = format_tag(CACHE_NAME, CACHE_VERSION)

__all__ = ["CACHE_FORMAT", "read_cache", "write_cache"]


def _checksum(payload: Any, source: str) -> str:
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), allow_nan=True)
    return hashlib.sha256(f"{source}\n{text}".encode()).hexdigest()


def write_cache(path: str | Path, payload: dict[str, Any], source: str) -> Path:
    """Write ``payload`` (plain JSON data) learned from ``source`` (a content hash) to ``path``,
    atomically, with its checksum."""
    return write_versioned(path, {"format": CACHE_FORMAT, "source_sha256": source,
                                  "sha256": _checksum(payload, source), "payload": payload})


def read_cache(path: str | Path, source: str) -> dict[str, Any] | None:
    """The payload of the cache file ``path`` if it was written for ``source`` and is unchanged since
    (its checksum matches); None otherwise (module docstring)."""
    try:
        doc = check_format(read_json(path), CACHE_NAME, CACHE_VERSION, str(path))
    except SkillFileError:
        return None
    payload = doc.get("payload")
    if doc.get("source_sha256") != source or not isinstance(payload, dict):
        return None
    if doc.get("sha256") != _checksum(payload, source):
        return None
    return payload
