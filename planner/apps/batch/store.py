"""The results of a batch in SQLite: one row per (task, variant), written as each one finishes.

Tables: ``meta`` (batch name, digest, batch file as JSON), ``tasks`` (one row per generated task
with its difficulty measures and task JSON) and ``results`` (OMPL-like: task id, tool, variant,
status ``solved|violated|infeasible|error|timeout``, reason, per-stage planning times [s], number of
QPs, violation maxima, clearances [m], goal error [m], path length [m], pushes, switches, worker, start
and finish times (Unix seconds); every plan metric is kept in ``metrics_json``; with ``--simulate``
the executions of a solved plan: open loop (``open_loop_*``, also under the schema-1 names
``sim_*``) and closed loop (``closed_loop_*``), each with a status, a reason and a wall time). The
journal is WAL; each row is committed on its own, so a process killed at any point loses at most
the rows not yet written, and ``(task_id, variant)`` is the primary key: a row can never be stored
twice (a row run again, ``batch run --retry``, is replaced by its new result, :meth:`ResultStore.put`).

Schema 2 added the execution columns. A schema-1 file (no ``open_loop_*``/``closed_loop_*``
columns) still opens for reading (:meth:`ResultStore.rows` gives its ``sim_final_error`` as
``open_loop_error``); :func:`tooltransfer.planner.apps.batch.store_settings.open_batch_store` refuses to resume it.
"""

from __future__ import annotations

import json
import os
import socket
import sqlite3
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from textwrap import shorten
from typing import Any

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.store_file import (
    StoreError,
    check_rows,
    check_schema,
    columns,
    connect_readonly,
    store_error,
    tables,
)
from tooltransfer.regular_file import file_kind

SCHEMA_VERSION = "2"
#: Schemas :class:`ResultStore` can read (only the current one is resumed).
READABLE_SCHEMAS = ("1", "2")

#: Columns of ``results`` and their SQL types.
RESULT_COLUMNS: dict[str, str] = {
    "task_id": "TEXT NOT NULL", "variant": "TEXT NOT NULL", "oe": "TEXT", "ss": "TEXT", "tool": "TEXT",
    "status": "TEXT NOT NULL", "reason": "TEXT",
    "time_total": "REAL", "cpu_time": "REAL", "time_skills": "REAL", "time_oe": "REAL",
    "time_switches_and_timing": "REAL", "n_qp": "REAL",
    "cone_violation_max": "REAL", "reach_violation_max": "REAL", "penetration_max": "REAL",
    "joint_limit_violation_max": "REAL", "obstacle_clearance_min": "REAL", "switch_clearance_min": "REAL",
    "switch_obstacle_clearance_min": "REAL", "goal_error": "REAL", "path_length": "REAL", "n_pushes": "REAL",
    "n_switches": "INTEGER", "duration": "REAL",
    "sim_final_error": "REAL", "sim_tool_deviation": "REAL", "sim_wall_time": "REAL", "sim_success": "INTEGER",
    "open_loop_status": "TEXT", "open_loop_reason": "TEXT", "open_loop_error": "REAL", "open_loop_wall_time": "REAL",
    "closed_loop_status": "TEXT", "closed_loop_reason": "TEXT", "closed_loop_error": "REAL",
    "closed_loop_pushes": "INTEGER", "closed_loop_switches": "INTEGER", "closed_loop_recontacts": "INTEGER",
    "closed_loop_replans": "INTEGER", "closed_loop_replan_time_median": "REAL", "closed_loop_replan_time_max": "REAL",
    "closed_loop_wall_time": "REAL", "closed_loop_seed": "INTEGER",
    "wall_time": "REAL", "worker": "TEXT", "started_at": "REAL", "finished_at": "REAL",
    "metrics_json": "TEXT", "detail": "TEXT",
}

TASK_COLUMNS: dict[str, str] = {
    "task_id": "TEXT PRIMARY KEY", "idx": "INTEGER", "tool": "TEXT", "n_obstacles": "INTEGER",
    "start_reach": "REAL", "target_reach": "REAL", "reach_margin": "REAL", "distance": "REAL", "task_json": "TEXT",
}

#: Every status a result row may have.
STATUSES = ("solved", "violated", "infeasible", "unknown", "error", "timeout")
#: The statuses that are a verdict of the planner on the task (``error`` and ``timeout``: the run gave none).
VERDICT_STATUSES = ("solved", "violated", "infeasible", "unknown")

_META_COLUMNS = {"key": "TEXT PRIMARY KEY", "value": "TEXT"}
#: The tables of a store, exactly (:func:`~tooltransfer.planner.apps.batch.store_file.check_schema`).
_SCHEMA = {"meta": _META_COLUMNS, "tasks": TASK_COLUMNS, "results": RESULT_COLUMNS}


class ResultStore:
    """A batch's SQLite file (created if missing).

    Opened for writing (the default), a new or empty file gets the tables; an existing one must be a
    store of this program exactly (:func:`~tooltransfer.planner.apps.batch.store_file.check_schema`:
    its tables and columns, no trigger or view) or an older schema's (read, never resumed), else it
    is refused before anything is written. Opened ``readonly``, nothing in the file changes
    (:func:`~tooltransfer.planner.apps.batch.store_file.connect_readonly`), and a file without a
    results table raises. SQLite's failures (a full disk, a damaged page, a read-only file) raise
    :class:`~tooltransfer.planner.apps.batch.store_file.StoreError` naming the file and the remedy.

    Args:
        path: the database file.
        readonly: open it for reading only.
        field: the option or argument that named the file, for messages (``--db``; ``db`` for a report).
    """

    def __init__(self, path: str | Path, *, readonly: bool = False, field: str = "--db") -> None:
        self.path = Path(path)
        self.field = field
        #: rows that could not be read (a note for the reader), or ""
        self.note = ""
        #: the (task id, variant) pairs being run again (:meth:`again`)
        self.retrying: frozenset[tuple[str, str]] = frozenset()
        self._copy: tempfile.TemporaryDirectory | None = None  # a private copy read instead (readonly)
        try:
            kind = file_kind(os.stat(self.path).st_mode)
        except OSError:
            kind = ""  # a new file (or one SQLite will name)
        if kind:  # a FIFO would block SQLite's first read for ever, a device is no store
            raise StoreError(field, self.path, "an SQLite results file (a regular file) or a new path", kind)
        if readonly:
            self.db, self.note, self._copy = connect_readonly(self.path, field)
            with self._guard():
                found = tables(self.db)
            if found and found.get("results") not in ("table", "view"):
                self.close()
                raise StoreError(field, self.path, "a results file written by `tooltransfer batch run`",
                                 f"an SQLite file with the tables {', '.join(sorted(found))} and no results table")
            with self._guard():
                have = {c[0] for c in columns(self.db, "results")} if found else set()
            missing = [c for c in ("task_id", "variant", "status") if found and c not in have]
            if missing:
                self.close()
                raise StoreError(field, self.path, "a results file written by `tooltransfer batch run`",
                                 f"a results table without the column {missing[0]}")
            #: opened read-only, the file holds no tables at all (nothing to report)
            self.empty = not found
        else:
            self.empty = False
            self._open_for_writing()
        with self._guard():
            version = self.meta().get("schema") if "meta" in tables(self.db) else None
        if version is None and not readonly:
            self.set_meta(schema=SCHEMA_VERSION)
            version = SCHEMA_VERSION
        elif version is not None and version not in READABLE_SCHEMAS:
            self.close()
            raise InputError(field, f"a results file of schema {' or '.join(READABLE_SCHEMAS)}", f"schema {version}")
        #: the file's schema (see the module docstring)
        self.schema = version or SCHEMA_VERSION

    def _open_for_writing(self) -> None:
        """Connect, check an existing file's schema exactly, and make the tables of a new one."""
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise StoreError(self.field, self.path, "a results file in a folder that can be made",
                             exc.strerror or str(exc)) from None
        with self._guard():
            self.db = sqlite3.connect(self.path, timeout=30.0)
            found = tables(self.db)
        if found:  # an existing store: exactly this program's, of this schema or the one before
            with self._guard():
                version = dict(self.db.execute("SELECT key, value FROM meta").fetchall()).get("schema") \
                    if found.get("meta") == "table" else None
            schema: dict[str, dict[str, str]] = dict(_SCHEMA)
            if version == "1":  # read (and refused on resume by open_batch_store), never written
                schema["results"] = {k: v for k, v in RESULT_COLUMNS.items()
                                     if not k.startswith(("open_loop", "closed_loop"))}
                if "tasks" not in found:
                    del schema["tasks"]
            try:
                with self._guard():
                    check_schema(self.db, self.path, self.field, schema, {"results": ("task_id", "variant")})
            except StoreError:
                self.close()
                raise
        with self._guard():
            self.db.execute("PRAGMA journal_mode=WAL")
            self.db.execute("PRAGMA synchronous=NORMAL")  # WAL + NORMAL: durable against a killed process
            if not found:
                cols = ", ".join(f"{k} {v}" for k, v in RESULT_COLUMNS.items())
                tcols = ", ".join(f"{k} {v}" for k, v in TASK_COLUMNS.items())
                with self.db:
                    self.db.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT)")
                    self.db.execute(f"CREATE TABLE tasks ({tcols})")
                    self.db.execute(f"CREATE TABLE results ({cols}, PRIMARY KEY (task_id, variant))")

    @contextmanager
    def _guard(self) -> Iterator[None]:
        """SQLite's failures as :class:`StoreError` naming the file (nothing stored is lost: each write is
        one transaction, rolled back whole)."""
        try:
            yield
        except sqlite3.IntegrityError:
            raise
        except sqlite3.Error as exc:
            raise store_error(exc, self.path, self.field) from None

    def check_rows(self) -> None:
        """Refuse a store holding a value of the wrong kind (text where a number belongs, an unknown
        status): before a run writes into it, and before a report computes with it.

        Raises:
            StoreError: naming the file, the row and the column.
        """
        found = tables(self.db)
        check_rows(self.db, self.path, self.field, "results", RESULT_COLUMNS, {"status": STATUSES})
        if found.get("tasks") == "table":
            check_rows(self.db, self.path, self.field, "tasks", TASK_COLUMNS)
        if found.get("meta") == "table":
            check_rows(self.db, self.path, self.field, "meta", {"key": "TEXT", "value": "TEXT"})

    def close(self) -> None:
        self.db.close()
        if self._copy is not None:
            self._copy.cleanup()
            self._copy = None

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def meta(self) -> dict[str, str]:
        """The ``meta`` table's keys and values (none in an empty file opened read-only)."""
        if self.empty:
            return {}
        with self._guard():
            return dict(self.db.execute("SELECT key, value FROM meta").fetchall())

    def set_meta(self, **values: str) -> None:
        with self._guard(), self.db:
            self.db.executemany("INSERT OR REPLACE INTO meta VALUES (?, ?)", values.items())

    def add_tasks(self, tasks: Iterable[dict[str, Any]]) -> None:
        """Record tasks (already recorded ids are kept as they are)."""
        keys = list(TASK_COLUMNS)
        sql = f"INSERT OR IGNORE INTO tasks ({', '.join(keys)}) VALUES ({', '.join('?' * len(keys))})"
        with self._guard(), self.db:
            self.db.executemany(sql, ([t.get(k) for k in keys] for t in tasks))

    def done(self) -> set[tuple[str, str]]:
        """The (task id, variant) pairs already stored."""
        with self._guard():
            return set(self.db.execute("SELECT task_id, variant FROM results").fetchall())

    def done_for(self, task_ids: Sequence[str]) -> set[tuple[str, str]]:
        """The (task id, variant) pairs already stored for these tasks."""
        out: set[tuple[str, str]] = set()
        with self._guard():
            for i in range(0, len(task_ids), 500):
                part = list(task_ids[i : i + 500])
                sql = f"SELECT task_id, variant FROM results WHERE task_id IN ({', '.join('?' * len(part))})"
                out.update(self.db.execute(sql, part).fetchall())
        return out

    def put(self, row: dict[str, Any]) -> bool:
        """Store one result row and commit it; False where a row run again (:meth:`again`) is kept instead.

        A stored key raises ``sqlite3.IntegrityError`` unless it is run again: then the new row replaces the
        stored one (its ``detail`` names the status it replaces), except where the stored row is a verdict
        (:data:`VERDICT_STATUSES`) and the new run gave none (``error``, ``timeout``): the stored row is kept,
        its ``detail`` saying how the new run ended, so that a retry never loses a verdict already computed.
        :class:`~tooltransfer.planner.apps.batch.store_file.StoreError` when it cannot be written (the rows
        stored before are kept)."""
        key = (row.get("task_id"), row.get("variant"))
        with self._guard(), self.db:
            if key in self.retrying:
                where = "FROM results WHERE task_id = ? AND variant = ?"
                old = self.db.execute(f"SELECT status, reason, detail {where}", key).fetchone()
                if old is not None and old[0] in VERDICT_STATUSES and row.get("status") not in VERDICT_STATUSES:
                    why = shorten(str(row.get("reason") or ""), 300)
                    note = f"run again, it ended {row.get('status')} ({why}): this row is kept"
                    self.db.execute("UPDATE results SET detail = ? WHERE task_id = ? AND variant = ?",
                                    (_joined(old[2], note), *key))
                    return False
                if old is not None:
                    note = f"replaces a row of an earlier run: {old[0]} ({shorten(str(old[1] or ''), 300)})"
                    row = {**row, "detail": _joined(row.get("detail"), note)}
                    self.db.execute(f"DELETE {where}", key)
            keys = [k for k in RESULT_COLUMNS if k in row]
            vals = [json.dumps(row[k]) if isinstance(row[k], dict | list) else row[k] for k in keys]
            self.db.execute(f"INSERT INTO results ({', '.join(keys)}) VALUES ({', '.join('?' * len(keys))})", vals)
        return True

    def again(self, statuses: Sequence[str]) -> frozenset[tuple[str, str]]:
        """The (task id, variant) pairs stored with these statuses, to be run again (``batch run --retry``):
        :meth:`put` replaces each one's row as its new result comes (or keeps it, see there); until then the
        stored row stays, so a retry stopped half way loses nothing."""
        with self._guard():
            sql = f"SELECT task_id, variant FROM results WHERE status IN ({', '.join('?' * len(statuses))})"
            pairs = frozenset(self.db.execute(sql, list(statuses)).fetchall())
        self.retrying = self.retrying | pairs
        return pairs

    def rows(self) -> list[dict[str, Any]]:
        """Every result joined with its task's difficulty measures, in task and variant order."""
        if self.empty:
            return []
        with self._guard():
            if tables(self.db).get("tasks") == "table":
                cur = self.db.execute(
                    "SELECT r.*, t.n_obstacles, t.start_reach, t.target_reach, t.reach_margin, t.distance, t.idx "
                    "FROM results r LEFT JOIN tasks t USING (task_id) ORDER BY t.idx, r.task_id, r.variant")
            else:  # a schema-1 file without tasks
                cur = self.db.execute("SELECT * FROM results ORDER BY task_id, variant")
            names = [d[0] for d in cur.description]
            rows = [dict(zip(names, r, strict=True)) for r in cur.fetchall()]
        if "open_loop_error" not in names:  # schema 1: its simulation was open loop
            for r in rows:
                if r.get("sim_final_error") is not None:
                    r.update(open_loop_status="done", open_loop_error=r["sim_final_error"],
                             open_loop_wall_time=r.get("sim_wall_time"))
        return rows

    def task_documents(self) -> dict[str, dict[str, Any]]:
        """Each recorded task's task-file fields by task id (``{}`` without a tasks table; a task whose
        JSON does not read as an object is left out)."""
        if self.empty or tables(self.db).get("tasks") != "table":
            return {}
        with self._guard():
            found = self.db.execute("SELECT task_id, task_json FROM tasks").fetchall()
        out: dict[str, dict[str, Any]] = {}
        for tid, text in found:
            try:
                doc = json.loads(text or "null")
            except ValueError:
                continue
            if isinstance(doc, dict):
                out[str(tid)] = doc
        return out

    def count(self) -> int:
        if self.empty:
            return 0
        with self._guard():
            return int(self.db.execute("SELECT COUNT(*) FROM results").fetchone()[0])


@contextmanager
def lock_store(path: str | Path) -> Iterator[Path]:
    """Hold the exclusive lock of the store ``path`` while a ``batch run`` writes it: an advisory lock
    (``flock``) on ``<path>.lock``, released when the process ends however it ends (a SIGKILL too),
    so a second run on the same store is refused at once instead of computing every pair again.

    Raises:
        InputError: naming ``--db``, the store and the process holding it.
    """
    p = Path(path)
    lock = p.with_name(p.name + ".lock")
    try:
        lock.parent.mkdir(parents=True, exist_ok=True)
        fh = open(lock, "a+")  # held open for the lock's lifetime
    except OSError as exc:
        raise InputError("--db", "a results file whose folder is writable (for its lock file)",
                         f"{lock}: {exc.strerror}") from None
    try:
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock (documented)
            yield lock
            return
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.seek(0)
            holder = fh.read().strip()[:100] or "another process"
            raise InputError(f"--db {p}", "a results file no other `tooltransfer batch run` is writing (wait for it "
                             f"to finish, or run into another --db; lock {lock.name})", f"in use by {holder}") from None
        fh.seek(0)
        fh.truncate()
        fh.write(f"process {os.getpid()} on {socket.gethostname()}\n")
        fh.flush()
        yield lock
    finally:
        fh.close()  # releases the lock


def _joined(detail: object, note: str) -> str:
    """A row's ``detail`` with ``note`` added as its last line (the whole kept under 8000 characters)."""
    return (f"{detail}\n{note}" if detail else note)[-8000:]
