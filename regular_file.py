"""Reading a file as data: a regular file only, of a bounded size, never blocking, and (for the files
of a folder such as a dataset) never outside that folder.

Why: a path in a task file or a dataset may name anything the process can open. A FIFO or
``/proc/kmsg`` blocks the reader forever, ``/dev/zero`` or a sparse file of 8 GB (``truncate -s 8G``)
reads until memory runs out, and a dataset's ``meta.yaml`` that links to ``/etc/passwd`` or a token
file would have that file's first line quoted in an error message. So every reader of the project's
file formats goes through :func:`read_regular`:

1. the path, with links resolved, stays inside ``inside`` when one is given (a dataset's files stay
   in the dataset) and out of the kernel's interfaces (``/proc``, ``/sys``);
2. ``os.stat`` (which never blocks) says it is a regular file of at most ``max_bytes``: a folder, a
   FIFO, a device or a socket is refused by its kind, a larger file by its size, before a byte is read;
3. it is opened non-blocking and checked again on the open descriptor (a file swapped in between),
   and at most ``max_bytes + 1`` bytes are read, so a file that grows, or a kernel file that reports
   size 0, cannot make the read unbounded.

Every refusal is ``error(path, "<file>", expected, got)``: the file, what was expected and what it
is, never its content.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable
from pathlib import Path

#: ``error(path, where, expected, got)``: the caller's exception for a refused file.
Error = Callable[[str, str, str, object], Exception]

#: Where the kernel's interfaces live: their "regular" files are not data (``/proc/kmsg`` blocks,
#: ``/proc/kcore`` is as large as the address space). Devices (``/dev/zero``) are refused by their kind.
KERNEL_FOLDERS = ("/proc", "/sys")

__all__ = ["KERNEL_FOLDERS", "file_kind", "is_inside", "read_regular", "size_text"]


def size_text(n: int) -> str:
    """A size in bytes for a message: ``"32 MB"``, ``"2.5 kB"``, ``"12 bytes"``."""
    for unit, scale in (("GB", 2**30), ("MB", 2**20), ("kB", 2**10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n} bytes"


def file_kind(mode: int) -> str:
    """What a file of ``st_mode`` ``mode`` is, in words, when it is not a regular file ("" when it is)."""
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "" if stat.S_ISREG(mode) else "not a regular file"


def is_inside(path: str | Path, folder: str | Path) -> bool:
    """Whether ``path``, its links resolved, lies in ``folder`` (its links resolved too)."""
    real, base = os.path.realpath(path), os.path.realpath(folder)
    return real == base or real.startswith(base.rstrip(os.sep) + os.sep)


def _kernel(path: str | Path) -> bool:
    real = os.path.realpath(path)
    return any(real == k or real.startswith(k + "/") for k in KERNEL_FOLDERS)


def read_regular(path: str | Path, error: Error, what: str, max_bytes: int, *, inside: str | Path | None = None,
                 where: str = "<file>") -> bytes:
    """The bytes of the regular file ``path`` (module docstring), at most ``max_bytes``.

    Args:
        error: builds the exception raised for a refused file: ``error(path, where, expected, got)``.
        what: the kind of file in messages (``"meta.yaml"``, ``"CSV file"``).
        inside: a folder the file must lie in, links resolved (None: anywhere but the kernel's folders).
        where: the place in ``path`` the messages name (``"<file>"``).
    """
    p = str(path)
    if inside is not None and not is_inside(p, inside):
        raise error(p, where, f"a {what} inside {inside}", "a path that leads outside it (a link, or ..)")
    if _kernel(p):
        raise error(p, where, f"a {what} (a regular file of data)", "a file of the kernel's interfaces "
                    f"({', '.join(KERNEL_FOLDERS)})")
    try:
        st = os.stat(p)
    except OSError as exc:
        raise error(p, where, f"a readable {what}", exc.strerror or type(exc).__name__) from None
    kind = file_kind(st.st_mode)
    if kind:
        raise error(p, where, f"a {what} (a regular file)", kind)
    if st.st_size > max_bytes:
        raise error(p, where, f"a {what} of at most {size_text(max_bytes)}", size_text(st.st_size))
    try:
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0))
    except OSError as exc:
        raise error(p, where, f"a readable {what}", exc.strerror or type(exc).__name__) from None
    try:
        kind = file_kind(os.fstat(fd).st_mode)
        if kind:
            raise error(p, where, f"a {what} (a regular file)", f"{kind} (replaced while opened)")
        chunks, n = [], 0
        while n <= max_bytes:
            try:
                chunk = os.read(fd, min(2**20, max_bytes + 1 - n))
            except BlockingIOError:
                raise error(p, where, f"a {what} (a regular file of data)", "a file that blocks when read") from None
            except OSError as exc:
                raise error(p, where, f"a readable {what}", exc.strerror or type(exc).__name__) from None
            if not chunk:
                break
            chunks.append(chunk)
            n += len(chunk)
    finally:
        os.close(fd)
    if n > max_bytes:
        raise error(p, where, f"a {what} of at most {size_text(max_bytes)}", "a larger file (it grew while read)")
    return b"".join(chunks)
