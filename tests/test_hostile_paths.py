"""Hostile input, class 3 of issue 16 (paths): an output option naming a folder, a missing folder,
a file as a folder, a place that cannot be written or a name too long ends in exit 2 with one line
naming the option and the path, before any work and leaving nothing behind; a task's name used as
a file name is sanitised (no escape from the folder, bounded length); outputs are written
atomically (a writer that fails leaves the old file and no temporary one). Hypothesis strategies
are derandomized.
"""

from __future__ import annotations

import errno
import json
import os
import re
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tooltransfer.atomic import atomic_path, write_bytes
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.apps.cli_output import file_stem
from tooltransfer.problems.task import TaskFileError, task_from_dict

ROOT = Path(__file__).resolve().parent.parent
TASK = ROOT / "problems" / "paper" / "transfer_tool2.yaml"
DATA = ROOT / "problems" / "data" / "finger_demos"
BATCH = ROOT / "problems" / "batch" / "small.yaml"
SETTINGS = settings(derandomize=True, deadline=None, max_examples=80,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])

# (command line before the option, the option as typed, as named in the message, the file's suffix)
FILE_OUTPUTS = [
    (["solve", str(TASK)], "-o", "-o/--out", ".json"),
    (["solve", str(TASK)], "--plot", "--plot", ".png"),
    (["learn", str(DATA)], "--out", "-o/--out", ".json"),
    (["simulate", "plan.json"], "--figure", "--figure", ".png"),
    (["simulate", "plan.json"], "--gif", "--gif", ".gif"),
    (["export", "plan.json", "--format", "csv"], "-o", "-o/--out", ".csv"),
    (["segment", str(DATA)], "--figure", "--figure", ".png"),
    (["schema"], "--out", "--out", ".json"),
    (["tools"], "--out", "--out", ".png"),
    (["batch", "run", str(BATCH), "-q"], "--db", "--db", ".sqlite"),
    (["choose", str(TASK), "--tools", "finger"], "-o", "-o", ".json"),
]
FOLDER_OUTPUTS = [
    (["compare", str(TASK)], "--out", "--out"),
    (["paper"], "--out", "--out"),
    (["demos", "--n", "1"], "--out", "--out"),
    (["batch", "generate", str(BATCH)], "--out", "--out"),
    (["batch", "report", "results.sqlite"], "--out", "--out"),
    (["choose", str(TASK), "--tools", "finger"], "--out", "--out"),
]


def _bad_file_path(tmp: Path, kind: str, suffix: str) -> Path:
    (tmp / "a_folder").mkdir(exist_ok=True)
    (tmp / "a_file").write_text("x")
    return {
        "folder": tmp / "a_folder",
        "missing folder": tmp / "nope" / "deeper" / f"out{suffix}",
        "file as folder": tmp / "a_file" / f"out{suffix}",
        "unwritable": Path("/proc") / f"tooltransfer-out{suffix}",
        "name too long": tmp / ("n" * 300 + suffix),
    }[kind]


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    capsys.readouterr()
    start = time.perf_counter()
    code = main(argv)
    assert time.perf_counter() - start < 5  # refused before any work
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    return code, err.strip()


FIGURES = [(h, o, n) for h, o, n, suffix, in FILE_OUTPUTS if suffix == ".png"]


@pytest.mark.parametrize(("head", "option", "named"), FIGURES, ids=[f"{h[0]} {o}" for h, o, _ in FIGURES])
def test_a_figure_path_without_a_figure_format_exits_2_before_any_work(tmp_path: Path, capsys, head: list[str],
                                                                      option: str, named: str) -> None:
    """The format is taken from the name's ending: ``--plot fig`` was an internal error after the solve."""
    code, err = _run([*head, option, str(tmp_path / "figure")], capsys)
    assert code == 2, err
    assert err.startswith(f"tooltransfer: error: {named}: expected a figure file name ending in .png"), err
    assert not list(tmp_path.iterdir())


def _listing(tmp: Path) -> set[str]:
    return {str(p.relative_to(tmp)) for p in tmp.rglob("*")}


FILE_KINDS = ["folder", "missing folder", "file as folder", "unwritable", "name too long"]
FILE_CASES = [(h, o, n, s, k) for h, o, n, s in FILE_OUTPUTS for k in FILE_KINDS
              if not (o == "--db" and k == "missing folder")]  # a results store makes its folders


FILE_IDS = [f"{' '.join(h[:2] if h[0] == 'batch' else h[:1])} {o} {k}" for h, o, _, _, k in FILE_CASES]


@pytest.mark.parametrize(("head", "option", "named", "suffix", "kind"), FILE_CASES, ids=FILE_IDS)
def test_bad_file_outputs_exit_2_naming_the_option_and_the_path(tmp_path: Path, capsys, head: list[str], option: str,
                                                                 named: str, suffix: str, kind: str) -> None:
    path = _bad_file_path(tmp_path, kind, suffix)
    before = _listing(tmp_path)
    code, err = _run([*head, option, str(path)], capsys)
    assert code == 2
    assert err.startswith(f"tooltransfer: error: {named}: expected ") and str(path)[:60] in err, err
    assert _listing(tmp_path) == before  # nothing made, nothing left (no probe, no folder)


@pytest.mark.parametrize("kind", ["file", "file as folder", "unwritable", "name too long"])
@pytest.mark.parametrize(("head", "option", "named"), FOLDER_OUTPUTS,
                         ids=[" ".join(h[:2]) for h, _, _ in FOLDER_OUTPUTS])
def test_bad_folder_outputs_exit_2_naming_the_option_and_the_path(tmp_path: Path, capsys, head: list[str], option: str,
                                                                   named: str, kind: str) -> None:
    (tmp_path / "a_file").write_text("x")
    path = {"file": tmp_path / "a_file", "file as folder": tmp_path / "a_file" / "sub",
            "unwritable": Path("/proc") / "tooltransfer-out", "name too long": tmp_path / ("n" * 300)}[kind]
    before = _listing(tmp_path)
    code, err = _run([*head, option, str(path)], capsys)
    assert code == 2
    assert err.startswith(f"tooltransfer: error: {named}: expected ") and str(path)[:60] in err, err
    assert _listing(tmp_path) == before


NAME_RE = re.compile(r"^[A-Za-z0-9_-][A-Za-z0-9._-]{0,99}$")


@SETTINGS
@given(st.text(max_size=300))
def test_any_text_gives_a_safe_file_stem(name: str) -> None:
    stem = file_stem(name)
    assert NAME_RE.match(stem), stem
    assert Path(f"plan_{stem}.png").parent == Path(".") and ".." not in Path(stem).parts


@SETTINGS
@given(st.one_of(st.text(max_size=150), st.sampled_from(["../../../x", "/etc/passwd", "a/b", "..", ".", "a\\b",
                                                         "a\x00b", "a\nb", "n" * 101, "ok name", "plan.v2"])))
def test_task_names_are_refused_or_safe_as_file_names(name: str) -> None:
    base = {"tool": "slope", "start": [0.045, 0.12], "target": [-0.052, 0.19], "skills": {"dataset": "d"}}
    try:
        task = task_from_dict({**base, "name": name}, "t.yaml")
    except TaskFileError as exc:
        assert str(exc).startswith("t.yaml: name: expected") and len(str(exc)) < 400
        return
    assert "/" not in task.name and "\\" not in task.name and len(task.name) <= 100
    assert task.name.strip(".") and all(ord(c) >= 32 and ord(c) != 127 for c in task.name)
    assert NAME_RE.match(file_stem(task.name))


def test_solve_plot_without_out_writes_a_sanitised_name_in_the_working_folder(tmp_path: Path, monkeypatch,
                                                                              capsys) -> None:
    import yaml

    data = yaml.safe_load(TASK.read_text())
    data.update(name="odd name ü.v2", skills={"dataset": str(DATA)}, variants={"oe": "qp", "ss": "arch"})
    work = tmp_path / "work"
    work.mkdir()
    task = tmp_path / "task.yaml"
    task.write_text(yaml.safe_dump(data, allow_unicode=True))
    monkeypatch.chdir(work)
    assert main(["solve", str(task), "--plot", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["figure"] == "plan_odd_name_.v2.png"
    assert [p.name for p in work.iterdir()] == ["plan_odd_name_.v2.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["task.yaml", "work"]


# --- atomic writes --------------------------------------------------------------------------------

def _no_temporaries(folder: Path) -> None:
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".")], list(folder.iterdir())


@SETTINGS
@given(st.binary(max_size=5000), st.binary(max_size=5000))
def test_atomic_writes_replace_the_whole_file(tmp_path_factory, old: bytes, new: bytes) -> None:
    folder = tmp_path_factory.mktemp("atomic")
    target = folder / "out.bin"
    write_bytes(target, old)
    assert write_bytes(target, new) == target and target.read_bytes() == new
    _no_temporaries(folder)


@pytest.mark.parametrize("failure", [KeyboardInterrupt, OSError])
def test_a_failing_writer_leaves_the_old_file_and_no_temporary(tmp_path: Path, failure: type) -> None:
    target = tmp_path / "fig.png"
    target.write_bytes(b"old")
    with pytest.raises(failure), atomic_path(target) as tmp:
        tmp.write_bytes(b"half of the n")
        raise failure(errno.ENOSPC, "No space left on device") if failure is OSError else failure()
    assert target.read_bytes() == b"old"
    _no_temporaries(tmp_path)


def _disk_full(monkeypatch: pytest.MonkeyPatch) -> None:
    """The next flush to disk fails as on a full disk (after the content went to the temporary file)."""
    import tooltransfer.atomic

    def full(path: Path) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(tooltransfer.atomic, "_fsync", full)


def test_plan_and_skills_files_are_never_half_written(tmp_path: Path, monkeypatch) -> None:
    from tooltransfer.planner.learning.skills import learn_skills
    from tooltransfer.planner.planning.plan import Plan

    plan = Plan(status="infeasible", variant={"oe": "qp", "ss": "arch"}, task={"name": "x"}, platform={}, object={},
                tool={}, obstacles=[], reason="why")
    skills = learn_skills(DATA)
    plan_file, skills_file = tmp_path / "plan.json", tmp_path / "skills.json"
    plan_file.write_text("old plan")
    skills_file.write_text("old skills")
    with monkeypatch.context() as m:
        _disk_full(m)
        with pytest.raises(OSError) as exc:
            plan.write(plan_file)
        assert exc.value.filename == str(plan_file)
        with pytest.raises(OSError):
            skills.save(skills_file)
    assert plan_file.read_text() == "old plan" and skills_file.read_text() == "old skills"
    _no_temporaries(tmp_path)
    plan.write(plan_file)
    skills.save(skills_file)
    assert json.loads(plan_file.read_text())["reason"] == "why" and json.loads(skills_file.read_text())["oe"]


def test_dmp_skill_files_are_never_half_written(tmp_path: Path, monkeypatch) -> None:
    import numpy as np

    from tooltransfer.dmp import DMP

    t = np.linspace(0, 1, 50)
    d = DMP(n_dims=2, n_basis=10).fit(t, np.column_stack([t, t**2]))
    target = tmp_path / "dmp.json"
    target.write_text("old")

    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    with monkeypatch.context() as m:
        m.setattr(os, "fsync", full)
        with pytest.raises(OSError):
            d.save(target)
    assert target.read_text() == "old"
    _no_temporaries(tmp_path)
    d.save(target)
    assert DMP.load(target).n_basis == 10


def test_a_full_disk_is_one_line_naming_the_file(tmp_path: Path, monkeypatch, capsys) -> None:
    out = tmp_path / "schema.json"
    _disk_full(monkeypatch)
    code, err = _run(["schema", "--out", str(out)], capsys)
    assert code == 2 and f"{out}: No space left on device" in err
    assert not out.exists()
    _no_temporaries(tmp_path)
