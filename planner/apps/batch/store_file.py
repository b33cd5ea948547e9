"""The SQLite file under a :class:`~tooltransfer.planner.apps.batch.store.ResultStore`: opening it for reading
without changing it, checking that a file to be written is a store of this program exactly, and turning
SQLite's failures into messages that name the file and what to do.

Why: a results file outlives the run that wrote it. It may be copied to a read-only share, reach a
full disk, be damaged, or be another program's file (or carry an SQL trigger that deletes rows on
insert). A report must not change it (a connection that creates the tables or switches the journal
writes to the file), and a run must not write into anything it did not create.

- :func:`connect_readonly`: ``file:PATH?mode=ro`` (SQLite refuses any write), and ``immutable=1``
  where there is no journal to fold in (nothing is locked, and no ``-wal``/``-shm`` file is created
  beside it: a read-only file or folder reads as well). A store a killed run left with rows in its
  ``-wal`` (or a hot ``-journal``) is copied with it into a temporary folder and read there, so no
  file beside it changes; a store a live ``batch run`` is writing (it holds the store's lock) is read
  through SQLite's reader protocol, beside that run (whose shared-memory index ``-shm`` changes as
  it writes). Where neither works (no room for a copy, and a read-only folder without the index), the
  file is read without its journal and the caller is told.
- :func:`check_schema`: the tables, their columns (name, declared type, NOT NULL, primary key), no
  trigger, no view and no index this program does not make; :func:`check_rows`: every value of
  the right storage class (numbers where numbers belong).
- :func:`store_error`: SQLite's exception as a :class:`StoreError` (a full disk, a damaged page,
  a file that is not a database, a read-only file, a lock) naming the file and the remedy.
"""

from __future__ import annotations

import os
import shutil
import sqlite3
import stat
import tempfile
from collections.abc import Mapping
from pathlib import Path
from urllib.parse import quote

from tooltransfer.errors import InputError

__all__ = ["StoreError", "check_rows", "check_schema", "columns", "connect_readonly", "store_error", "tables"]

#: Storage classes (``typeof``) allowed per declared SQL type.
_CLASSES = {"TEXT": ("text", "null"), "REAL": ("real", "integer", "null"), "INTEGER": ("integer", "null")}


class StoreError(InputError):
    """A results file that cannot be read or written as a store (exit code 2): names the file, what
    is wrong and what to do.

    Attributes:
        path: the file.
    """

    def __init__(self, field: str, path: Path, expected: str, got: str) -> None:
        self.path = path
        super().__init__(f"{field} {path}", expected, got)


def store_error(exc: sqlite3.Error, path: Path, field: str) -> StoreError:
    """SQLite's ``exc`` on the file ``path`` (given as the option or argument ``field``) in words."""
    text = str(exc)
    low = text.lower()
    if "disk is full" in low or "disk i/o error" in low:
        return StoreError(field, path, "room on its disk to write the results (free some space, then carry on with "
                          "`batch run ... --resume`: the rows stored so far are kept)", f"a full disk (sqlite: {text})")
    if "not a database" in low or "encrypted" in low:
        return StoreError(field, path, "an SQLite results file written by `tooltransfer batch run` (or a new file)",
                          f"a file that is not an SQLite database, or one damaged from its first page (sqlite: {text})")
    if "malformed" in low:
        return StoreError(field, path, "an undamaged SQLite results file (keep this one; `sqlite3 FILE .recover | "
                          "sqlite3 NEW` saves what it can; or run into a new file)", f"a damaged file (sqlite: {text})")
    if "readonly" in low or "read-only" in low:
        return StoreError(field, path, "a results file this process may write (and its folder: SQLite writes a "
                          "journal beside it), or a new file", f"a read-only file (sqlite: {text})")
    if "locked" in low or "busy" in low:
        return StoreError(field, path, "a results file no other process is writing", f"a locked file (sqlite: {text})")
    return StoreError(field, path, "a readable SQLite results file", f"sqlite: {text}")


def _uri(path: Path, immutable: bool) -> str:
    return f"file:{quote(str(path.absolute()))}?mode=ro" + ("&immutable=1" if immutable else "")


def _size(path: Path) -> int:
    """The size of the regular file ``path`` [bytes], 0 when there is none."""
    try:
        st = path.stat()
    except OSError:
        return 0
    return st.st_size if stat.S_ISREG(st.st_mode) else 0


def _writer_alive(path: Path) -> bool:
    """Whether a ``batch run`` holds the store's lock (:func:`~tooltransfer.planner.apps.batch.store.lock_store`):
    asked without waiting, the lock file opened for reading only."""
    try:
        import fcntl

        fd = os.open(path.with_name(path.name + ".lock"), os.O_RDONLY | os.O_NONBLOCK)
    except (ImportError, OSError):
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError:
        return True
    finally:
        os.close(fd)  # releases a lock taken
    return False


def _private_copy(path: Path, logs: list[Path]) -> tempfile.TemporaryDirectory:
    """A temporary folder holding copies of ``path`` and its journals ``logs`` (SQLite folds them in there)."""
    folder = tempfile.TemporaryDirectory(prefix="tooltransfer-report-")
    copy = Path(folder.name) / path.name
    try:
        shutil.copyfile(path, copy)
        for log in logs:
            shutil.copyfile(log, copy.with_name(copy.name + log.name[len(path.name):]))
    except BaseException:
        folder.cleanup()
        raise
    return folder


def connect_readonly(path: Path, field: str) -> tuple[sqlite3.Connection, str, tempfile.TemporaryDirectory | None]:
    """A connection that cannot change ``path`` (module docstring), a note for the reader ("" or why
    rows may be missing), and the temporary folder of a private copy it reads, if any (remove it
    with ``cleanup()`` after closing the connection).

    Raises:
        StoreError: not an SQLite file, or one that cannot be opened.
    """
    logs = [p for p in (path.with_name(path.name + "-wal"), path.with_name(path.name + "-journal")) if _size(p) > 0]
    note, copy = "", None
    try:
        if logs and not _writer_alive(path):  # a killed run's journal: folded in a private copy
            try:
                copy = _private_copy(path, logs)
            except OSError:
                copy = None  # no room for a copy: read through the journal in place
        target = Path(copy.name) / path.name if copy is not None else path
        db = sqlite3.connect(_uri(target, immutable=not logs), uri=True, timeout=30.0)
        try:
            tables(db)
        except sqlite3.OperationalError:
            if not logs or copy is not None:
                raise
            db.close()
            db = sqlite3.connect(_uri(path, immutable=True), uri=True)
            tables(db)
            note = (f"{logs[0].name} holds rows a run left in its journal that cannot be read here (the folder is "
                    "read-only): they are not shown (`batch run ... --resume` folds them into the file)")
    except sqlite3.Error as exc:
        if copy is not None:
            copy.cleanup()
        raise store_error(exc, path, field) from None
    return db, note, copy


def tables(db: sqlite3.Connection) -> dict[str, str]:
    """Every schema object but SQLite's own (``sqlite_*``): name -> type (table, view, trigger, index)."""
    return {name: kind for kind, name in db.execute("SELECT type, name FROM sqlite_master")
            if not name.startswith("sqlite_")}


def columns(db: sqlite3.Connection, table: str) -> list[tuple[str, str, bool, bool]]:
    """``(name, declared type, NOT NULL, in the primary key)`` of ``table``'s columns, in order."""
    return [(name, str(kind).upper(), bool(notnull), bool(pk))
            for _, name, kind, notnull, _, pk in db.execute(f"PRAGMA table_info({table})")]


def _declared(spec: str) -> tuple[str, bool, bool]:
    """A column definition of this program (``"TEXT NOT NULL"``) as ``(type, NOT NULL, PRIMARY KEY)``."""
    words = spec.upper().split()
    return words[0], "NOT" in words, "PRIMARY" in words


def check_schema(db: sqlite3.Connection, path: Path, field: str,
                 expected: Mapping[str, Mapping[str, str]], keys: Mapping[str, tuple[str, ...]]) -> None:
    """Refuse a file whose schema is not ``expected`` exactly: table -> column -> definition, in order;
    ``keys``: a table's composite primary key. Tables, views, triggers and indexes it does not name are
    refused (an index SQLite makes for a key, ``sqlite_autoindex_*``, is its own).

    Raises:
        StoreError: naming the file and the first difference.
    """
    def refuse(got: str) -> StoreError:
        return StoreError(field, path, "a results file written by `tooltransfer batch run` and nothing else (or a "
                          "new file)", got)

    objects = tables(db)
    other = {name: kind for name, kind in objects.items() if kind != "table" or name not in expected}
    if other:
        name = sorted(other)[0]
        raise refuse(f"a file with the {other[name]} {name!r}, which `batch run` does not make"
                     + (" (it would run on every write)" if other[name] == "trigger" else ""))
    for table, cols in expected.items():
        if table not in objects:
            raise refuse(f"a file without the {table!r} table")
        want = [(name, *_declared(spec)) for name, spec in cols.items()]
        key = keys.get(table, ())
        want = [(n, t, nn, pk or n in key) for n, t, nn, pk in want]
        got = columns(db, table)
        if got != want:
            diff = next(((w, g) for w, g in zip(want, got, strict=False) if w != g), None)
            what = (f"column {diff[1][0]!r} ({diff[1][1]}) where {diff[0][0]!r} ({diff[0][1]}) belongs" if diff
                    else f"{len(got)} columns instead of {len(want)}")
            raise refuse(f"a {table!r} table of other columns: {what}")


def check_rows(db: sqlite3.Connection, path: Path, field: str, table: str, declared: Mapping[str, str],
               allowed: Mapping[str, tuple[str, ...]] | None = None) -> None:
    """Refuse a ``table`` holding a value whose storage class its column's type in ``declared`` does not
    allow (text where a number belongs, a number for a name), or, for the columns in ``allowed``, a
    value outside their set. One pass over the table.

    Raises:
        StoreError: naming the file, the row's key and the column (not the value: the file is data).
    """
    present = {name for name, *_ in columns(db, table)}
    cases = []
    for name, spec in declared.items():
        if name not in present:
            continue
        classes = _CLASSES.get(_declared(spec)[0])
        if classes is not None:
            listed = ", ".join(f"'{c}'" for c in classes)
            cases.append(f"WHEN typeof({name}) NOT IN ({listed}) THEN '{name}:' || typeof({name})")
        if allowed and name in allowed:
            listed = ", ".join(f"'{v}'" for v in allowed[name])
            cases.append(f"WHEN {name} NOT IN ({listed}) THEN '{name}:value'")
    if not cases:
        return
    key = ", ".join(n for n in ("task_id", "variant", "key") if n in present) or "rowid"
    sql = f"SELECT {key}, bad FROM (SELECT *, CASE {' '.join(cases)} END AS bad FROM {table}) WHERE bad IS NOT NULL"
    try:
        row = db.execute(sql + " LIMIT 1").fetchone()
    except sqlite3.Error as exc:
        raise store_error(exc, path, field) from None
    if row is None:
        return
    *ids, bad = row
    column, _, kind = bad.partition(":")
    spec = _declared(declared[column])[0]
    want = ("a number" if spec in ("REAL", "INTEGER") else "text") if kind != "value" else \
        f"one of {', '.join((allowed or {})[column])}"
    where = ", ".join(f"{n} {str(v)[:60]!r}" for n, v in zip(key.split(", "), ids, strict=True))
    got = f"a {kind} value" if kind != "value" else "another value"
    raise StoreError(field, path, f"{want} in column {column} of every {table} row (a results file of this program, "
                     "unchanged: run into a new file)", f"{got} in the row {where}")
