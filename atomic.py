"""Writing output files atomically: the content goes to a temporary file beside the target, is
flushed to disk, and replaces the target in one step (:func:`os.replace`), so a reader (or a user
after a crash, a full disk or Ctrl-C) sees the old file or the whole new one, never half of one.

* :func:`write_text` / :func:`write_bytes`: the content in memory.
* :func:`atomic_path`: a context manager for writers that take a path (matplotlib, Pillow): it
  yields the temporary path (same folder, same suffix, so the format is still inferred from it)
  and moves it into place when the block ends without an exception; otherwise it is removed.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path


def _temporary(target: Path) -> Path:
    """A fresh hidden name beside ``target`` that keeps its suffix (``.plan.json.1f3a9c.tmp.json``),
    at most 255 bytes long."""
    tag = f".{os.getpid()}-{os.urandom(4).hex()}.tmp{target.suffix}"  # secrets.token_hex(4), without its imports
    stem = target.name.encode()[: 255 - len(tag.encode()) - 1].decode(errors="ignore")
    return target.with_name(f".{stem}{tag}")


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | Path, *, mkdir: bool = True) -> Iterator[Path]:
    """Yield a temporary path to write ``path``'s new content to; on a clean exit it replaces
    ``path`` (``mkdir``: the parent folders are made first), on an exception it is removed and
    ``path`` is left as it was."""
    target = Path(path)
    if mkdir:
        target.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary(target)
    try:
        yield tmp
        if not tmp.exists():  # the writer wrote nothing (e.g. a figure of no frames): nothing to replace
            raise FileNotFoundError(2, "the writer produced no file", str(target))
        _fsync(tmp)
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError) and exc.filename in (None, str(tmp)):  # a full disk: name the file meant
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        raise


def write_bytes(path: str | Path, data: bytes, *, mkdir: bool = True) -> Path:
    """Write ``data`` to ``path`` atomically (module docstring); returns the path."""
    target = Path(path)
    with atomic_path(target, mkdir=mkdir) as tmp:
        # O_EXCL: never through a file (or a link) that is already there; the mode follows the umask
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
    return target


def write_text(path: str | Path, text: str, *, encoding: str = "utf-8", mkdir: bool = True) -> Path:
    """Write ``text`` to ``path`` atomically (module docstring); returns the path."""
    return write_bytes(path, text.encode(encoding), mkdir=mkdir)


__all__ = ["atomic_path", "write_bytes", "write_text"]
