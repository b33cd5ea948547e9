"""Damaged, foreign and hostile results stores (real SQLite files): ``batch report`` opens them
read-only and leaves every file byte-identical; a run refuses a file that is not exactly a store of
this program (foreign tables, a trigger, a view, other columns, values of the wrong kind) before
writing; a full disk (a real tmpfs when the tests run as root, SQLite's page limit otherwise) and a
damaged page end in one message naming the file (exit code 2), and no stored row is lost."""

from __future__ import annotations

import hashlib
import os
import sqlite3
import subprocess
from collections.abc import Iterator
from contextlib import closing
from pathlib import Path

import pytest

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.executors import open_executor
from tooltransfer.planner.apps.batch.report import write_report
from tooltransfer.planner.apps.batch.runner import run_jobs
from tooltransfer.planner.apps.batch.store import ResultStore
from tooltransfer.planner.apps.batch.store_file import StoreError
from tooltransfer.planner.apps.batch.worker import Job
from tooltransfer.planner.apps.cli import main


def _store(path: Path, n: int = 6) -> Path:
    """A real store of ``n`` rows, closed (its write-ahead log folded in)."""
    with ResultStore(path) as store:
        store.set_meta(batch_name="b", batch_digest="d", simulate="off")
        store.add_tasks([{"task_id": f"t{i}", "idx": i, "tool": "slope", "n_obstacles": 1} for i in range(n)])
        for i in range(n):
            store.put({"task_id": f"t{i}", "variant": "qp/arch", "tool": "slope",
                       "status": "solved" if i % 3 else "infeasible", "reason": "", "time_total": 0.1 * (i + 1)})
    return path


def _digests(folder: Path) -> dict[str, str]:
    """Every file in ``folder``: name -> SHA-256 of its bytes."""
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir()) if p.is_file()}


def _keys(path: Path) -> list[tuple]:
    with closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True)) as c:
        return c.execute("SELECT task_id, variant, status FROM results ORDER BY task_id").fetchall()


def _foreign(path: Path, sql: str) -> Path:
    _store(path)
    with closing(sqlite3.connect(path)) as c:
        c.executescript(sql)
    return path


HOSTILE = {
    "a foreign table": "CREATE TABLE other (x TEXT); INSERT INTO other VALUES ('secret');",
    "a trigger that deletes rows": "CREATE TRIGGER wipe AFTER INSERT ON results BEGIN DELETE FROM results; END;",
    "a view": "CREATE VIEW v AS SELECT * FROM results;",
    "an index": "CREATE INDEX i ON results (status);",
    "an extra column": "ALTER TABLE results ADD COLUMN extra TEXT;",
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_foreign_store_is_refused_before_anything_is_written(tmp_path: Path, case: str) -> None:
    db = _foreign(tmp_path / "s.sqlite", HOSTILE[case])
    before, rows = _digests(tmp_path), _keys(db)
    with pytest.raises(StoreError, match="written by `tooltransfer batch run` and nothing else") as err:
        ResultStore(db)
    assert str(db) in str(err.value) and "--db" in str(err.value) and "secret" not in str(err.value)
    assert _digests(tmp_path) == before and _keys(db) == rows


def test_a_trigger_store_loses_no_row_on_resume(tmp_path: Path, capsys, small_batch) -> None:
    """The issue's case: `--resume` into a store whose trigger deletes every row on insert."""
    db = _foreign(tmp_path / "s.sqlite", HOSTILE["a trigger that deletes rows"])
    rows = _keys(db)
    code = main(["batch", "run", str(small_batch()), "--db", str(db), "--resume", "-q", "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "trigger 'wipe'" in err and str(db) in err and "internal error" not in err
    assert _keys(db) == rows


@pytest.mark.parametrize(("column", "value", "kind"), [("time_total", "fast", "text"), ("n_switches", "x", "text"),
                                                       ("task_id", b"\x01", "blob"), ("reason", b"\xff", "blob"),
                                                       ("status", "great", "value")])
def test_values_of_the_wrong_kind_are_refused_naming_row_and_column(tmp_path: Path, column: str, value: object,
                                                                    kind: str) -> None:
    db = _store(tmp_path / "s.sqlite")
    with closing(sqlite3.connect(db)) as c, c:
        c.execute(f"UPDATE results SET {column} = ? WHERE task_id = 't2'", (value,))
    with ResultStore(db) as store:
        with pytest.raises(StoreError, match=f"column {column} of every results row") as err:
            store.check_rows()
    before = _digests(tmp_path)
    assert ("'t2'" in str(err.value) or column == "task_id") and kind in str(err.value)
    # the report refuses it too, naming its own argument, and changes nothing
    with pytest.raises(StoreError, match=f"^db {db}"):
        write_report(db, None)
    assert main(["batch", "report", str(db)]) == 2
    assert _digests(tmp_path) == before


def test_resume_checks_the_rows_before_writing(tmp_path: Path, small_batch) -> None:
    from tooltransfer.planner.apps.batch.spec import load_batch
    from tooltransfer.planner.apps.batch.store_settings import open_batch_store

    spec = load_batch(small_batch())
    db = tmp_path / "s.sqlite"
    with ResultStore(db) as store:
        open_batch_store(store, spec, [], resume=False)
        store.put({"task_id": "t-00000", "variant": "mapping/arch", "status": "solved", "goal_error": 0.001})
    with closing(sqlite3.connect(db)) as c, c:
        c.execute("UPDATE results SET goal_error = 'NaN mm'")
    with ResultStore(db) as store, pytest.raises(StoreError, match="a number in column goal_error"):
        open_batch_store(store, spec, [], resume=True)
    assert _keys(db) == [("t-00000", "mapping/arch", "solved")]


def _report_cases(tmp: Path) -> Iterator[tuple[str, Path, int, str]]:
    """(name, file, exit code, a phrase of the output) of stores a report meets."""
    empty = tmp / "empty.sqlite"
    empty.touch()
    yield "an empty file", empty, 0, "an empty file, no results to report"
    bare = tmp / "bare.sqlite"
    with closing(sqlite3.connect(bare)) as c:
        c.execute("PRAGMA user_version = 1")  # a header page, no table
    yield "an SQLite file without tables", bare, 0, "no results yet"
    no_results = tmp / "noresults.sqlite"
    with closing(sqlite3.connect(no_results)) as c:
        c.execute("CREATE TABLE other (x)")
    yield "a file without a results table", no_results, 2, "the tables other and no results table"
    foreign = _foreign(tmp / "foreign.sqlite", HOSTILE["a foreign table"])
    yield "a store with a foreign table", foreign, 0, "6 results in"
    other = tmp / "other.sqlite"
    with closing(sqlite3.connect(other)) as c, c:
        c.execute("CREATE TABLE results (x TEXT)")
        c.execute("INSERT INTO results VALUES ('secret')")
    yield "another program's results table", other, 2, "a results table without the column task_id"
    text = tmp / "text.sqlite"
    text.write_text("not a database\n" * 100)
    yield "a text file", text, 2, "a file that is not an SQLite database"
    fresh = tmp / "fresh.sqlite"
    ResultStore(fresh).close()
    yield "a store without rows", fresh, 0, "no results yet"


def test_report_leaves_every_file_byte_identical(tmp_path: Path, capsys) -> None:
    for name, path, code, phrase in _report_cases(tmp_path):
        before = _digests(tmp_path)
        assert main(["batch", "report", str(path)]) == code, name
        out = capsys.readouterr()
        assert phrase in out.out + out.err, (name, out)
        assert "--db" not in out.out + out.err and "internal error" not in out.err, name
        assert _digests(tmp_path) == before, name  # no file changed, none created (no -wal, -shm)


def test_report_reads_a_read_only_store_in_a_read_only_folder(tmp_path: Path, capsys) -> None:
    db = _store(tmp_path / "s.sqlite")
    os.chmod(db, 0o444)
    os.chmod(tmp_path, 0o555)
    try:
        before = _digests(tmp_path)
        assert main(["batch", "report", str(db)]) == 0
        assert "6 results in" in capsys.readouterr().out
        assert _digests(tmp_path) == before
    finally:
        os.chmod(tmp_path, 0o755)
    # a store a killed run left with rows in its write-ahead log: read through the log, file and log unchanged
    live = tmp_path / "live.sqlite"
    store = _store(live, 2) and ResultStore(live)
    store.put({"task_id": "late", "variant": "qp/arch", "status": "solved"})
    wal = live.with_name(live.name + "-wal")
    assert wal.stat().st_size > 0
    digests = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (live, wal)}
    assert main(["batch", "report", str(live)]) == 0
    assert "3 results in" in capsys.readouterr().out
    assert {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (live, wal)} == digests
    store.close()


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A real tmpfs of 2 MB (root only; skipped where mounting is not allowed)."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mnt)],
                                           capture_output=True).returncode:
        pytest.skip("mounting a tmpfs needs root")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], check=False)


def _fill(folder: Path) -> None:
    """Fill the disk of ``folder`` to the last byte."""
    fd = os.open(folder / "filler", os.O_WRONLY | os.O_CREAT, 0o600)
    try:
        while os.write(fd, b"\1" * 4096):
            pass
    except OSError:
        pass
    finally:
        os.close(fd)


JOBS = [Job(f"n{i}", "v", entry="builtins:dict", args=({"status": "solved", "reason": "x" * 20000},), timeout=30)
        for i in range(40)]


def test_a_full_disk_stops_the_run_naming_the_file_and_keeps_the_rows(small_disk: Path) -> None:
    """A real full disk (tmpfs): the run stops with a StoreError naming the file and the remedy."""
    db = _store(small_disk / "s.sqlite")
    rows = _keys(db)
    with ResultStore(db) as store:
        _fill(small_disk)
        with open_executor(workers=1) as slots, pytest.raises(StoreError) as err:
            run_jobs(JOBS, store, slots, progress=False)
    msg = str(err.value)
    assert f"--db {db}" in msg and "full disk" in msg and "--resume" in msg
    (small_disk / "filler").unlink()
    assert set(rows) <= set(_keys(db))  # nothing stored before is lost


def test_a_page_limit_makes_writes_fail_as_on_a_full_disk(tmp_path: Path) -> None:
    """SQLite's SQLITE_FULL through ``PRAGMA max_page_count`` (where no tmpfs can be mounted)."""
    db = _store(tmp_path / "s.sqlite")
    rows = _keys(db)
    with ResultStore(db) as store:
        pages = store.db.execute("PRAGMA page_count").fetchone()[0]
        store.db.execute(f"PRAGMA max_page_count = {pages}")
        with open_executor(workers=1) as slots, pytest.raises(StoreError, match="full disk"):
            run_jobs(JOBS, store, slots, progress=False)
    assert set(rows) <= set(_keys(db))


def _damage(db: Path) -> None:
    """Overwrite the results table's root page with garbage (a real damaged page)."""
    with closing(sqlite3.connect(db)) as c:
        page = c.execute("SELECT rootpage FROM sqlite_master WHERE name = 'results'").fetchone()[0]
        size = c.execute("PRAGMA page_size").fetchone()[0]
    with open(db, "r+b") as fh:
        fh.seek((page - 1) * size)
        fh.write(b"\xa5" * size)


def test_a_damaged_page_is_one_message_naming_the_file(tmp_path: Path, capsys) -> None:
    db = _store(tmp_path / "s.sqlite", 40)
    _damage(db)
    before = _digests(tmp_path)
    assert main(["batch", "report", str(db)]) == 2
    err = capsys.readouterr().err
    assert "damaged file" in err and str(db) in err and "internal error" not in err and "Traceback" not in err
    assert _digests(tmp_path) == before
    with pytest.raises(StoreError, match="damaged file"):
        with ResultStore(db) as store:
            store.put({"task_id": "new", "variant": "v", "status": "solved"})
            store.count()


def test_report_names_its_own_argument(tmp_path: Path, capsys) -> None:
    assert main(["batch", "report", str(tmp_path / "missing.sqlite")]) == 2
    err = capsys.readouterr().err
    assert "db " in err and "--db" not in err and "no such file" in err
    with pytest.raises(InputError, match=r"^db "):
        write_report(tmp_path, None)


def _open_error(path: Path, readonly: bool) -> list:
    """``ResultStore(path)`` in a thread that must end within 10 s (a FIFO read would block it): what it raised."""
    import threading

    out: list = []

    def run() -> None:
        try:
            ResultStore(path, readonly=readonly).close()
        except StoreError as exc:
            out.append(exc)

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(10)
    assert not t.is_alive(), "blocked"
    return out


@pytest.mark.parametrize("make", ["fifo", "folder", "device"])
def test_a_store_that_is_not_a_regular_file_is_refused_at_once(tmp_path: Path, make: str) -> None:
    path = {"fifo": tmp_path / "s.sqlite", "folder": tmp_path, "device": Path("/dev/null")}[make]
    if make == "fifo":
        os.mkfifo(path)  # SQLite's first read of it would block for ever
    for readonly in (False, True):
        (err,) = _open_error(path, readonly)
        assert "regular file" in str(err) and str(path) in str(err)


def test_report_on_a_read_only_file_system(small_disk: Path, tmp_path: Path, capsys) -> None:
    """A real read-only mount (root bypasses file modes): a closed store is reported, and so is a store
    a killed run left with rows in its write-ahead log and no shared-memory index (read in a private
    copy: SQLite cannot make the index there)."""
    import shutil

    _store(small_disk / "closed.sqlite")
    live = tmp_path / "live.sqlite"
    store = ResultStore(_store(live, 2))
    store.put({"task_id": "late", "variant": "qp/arch", "status": "solved"})
    for suffix in ("", "-wal"):  # the files a SIGKILL leaves, without SQLite's shared-memory index
        shutil.copy(f"{live}{suffix}", small_disk / f"killed.sqlite{suffix}")
    store.close()
    assert subprocess.run(["mount", "-o", "remount,ro", str(small_disk)]).returncode == 0
    before = _digests(small_disk)
    assert main(["batch", "report", str(small_disk / "closed.sqlite")]) == 0
    assert "6 results in" in capsys.readouterr().out
    assert main(["batch", "report", str(small_disk / "killed.sqlite")]) == 0
    out = capsys.readouterr().out
    assert "3 results in" in out and "note:" not in out
    assert _digests(small_disk) == before


def test_report_of_a_killed_runs_store_changes_no_file(tmp_path: Path, capsys) -> None:
    """The files a SIGKILL leaves (the store, its write-ahead log with the last rows, SQLite's
    shared-memory index): the report shows every row, and no file beside the store changes."""
    import shutil

    live = tmp_path / "live" / "s.sqlite"
    live.parent.mkdir()
    store = ResultStore(_store(live, 2))
    store.put({"task_id": "late", "variant": "qp/arch", "status": "solved"})
    killed = tmp_path / "killed"
    killed.mkdir()
    for suffix in ("", "-wal", "-shm"):
        shutil.copy(f"{live}{suffix}", killed / f"s.sqlite{suffix}")
    store.close()
    before = _digests(killed)
    assert main(["batch", "report", str(killed / "s.sqlite")]) == 0
    assert "3 results in" in capsys.readouterr().out
    assert _digests(killed) == before


def test_report_beside_a_live_run_reads_its_latest_rows(tmp_path: Path, capsys) -> None:
    """A store a live run is writing (it holds the store's lock): read through SQLite's reader protocol,
    its latest rows included, the store and its log unchanged."""
    from tooltransfer.planner.apps.batch.store import lock_store

    db = _store(tmp_path / "s.sqlite", 2)
    with lock_store(db), ResultStore(db) as store:
        store.put({"task_id": "late", "variant": "qp/arch", "status": "solved"})
        wal = db.with_name(db.name + "-wal")
        before = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (db, wal)}
        assert main(["batch", "report", str(db)]) == 0
        assert "3 results in" in capsys.readouterr().out
        assert {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (db, wal)} == before
        from tooltransfer.planner.apps.batch.store_file import connect_readonly

        reader, note, copy = connect_readonly(db, "db")
        reader.close()
        assert copy is None and note == ""  # read in place, beside the writer, not from a copy
