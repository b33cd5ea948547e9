"""Bundled task files addressable by name (issue 18): ``tooltransfer tasks`` lists them, and ``solve``
takes a name such as ``paper/transfer_tool2`` from any folder."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tooltransfer.planner.apps.cli import main
from tooltransfer.problems.named import bundled_tasks, stated_outcome, task_file

ROOT = Path(__file__).resolve().parents[1]


def test_every_bundled_task_file_has_a_name() -> None:
    names = bundled_tasks()
    files = sorted([*(ROOT / "problems" / "paper").glob("*.yaml"), *(ROOT / "problems" / "hard").glob("*.yaml")])
    assert sorted(p.resolve() for p in names.values()) == [p.resolve() for p in files]
    assert "paper/transfer_tool2" in names and "hard/target_out_of_reach" in names
    assert task_file("paper/transfer_tool2.yaml") == names["paper/transfer_tool2"]
    assert task_file("no/such/task") == Path("no/such/task")  # left as given: reading it names the file


def test_tasks_lists_them_with_what_they_are(capsys) -> None:
    assert main(["tasks"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [ln.split()[0] for ln in lines] == list(bundled_tasks())
    assert all(len(ln.split()) > 1 for ln in lines)  # each with a description
    for line, path in zip(lines, bundled_tasks().values(), strict=True):  # and the outcome its file states
        assert line.endswith(f" (expected: {stated_outcome(path)})") and stated_outcome(path) is not None
    assert main(["tasks", "--paths"]) == 0
    assert all(Path(ln.split()[1]).is_file() for ln in capsys.readouterr().out.splitlines())


def test_solve_takes_a_name_from_another_folder(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["solve", "paper/transfer_tool2", "-o", "plan.json", "--json"]) == 0
    assert json.loads((tmp_path / "plan.json").read_text())["status"] == "solved"
    capsys.readouterr()
    assert main(["solve", "paper/not_a_task"]) == 2
    assert "paper/not_a_task" in capsys.readouterr().err


def test_load_task_takes_a_bundled_name_or_a_path_from_any_folder(tmp_path, monkeypatch) -> None:
    import tooltransfer as tt
    from tooltransfer.problems.task import TaskFileError

    monkeypatch.chdir(tmp_path)
    by_name = tt.load_task("paper/transfer_tool2")
    assert by_name.source == str(bundled_tasks()["paper/transfer_tool2"].resolve())
    assert tt.load_task("paper/transfer_tool2.yaml") == by_name
    # a file relative to the working folder comes first, even where it shadows a bundled name
    local = tmp_path / "paper" / "transfer_tool2.yaml"
    local.parent.mkdir()
    local.write_bytes(bundled_tasks()["paper/transfer_tool2"].read_bytes())
    assert tt.load_task("paper/transfer_tool2.yaml").source == str(local.resolve())
    with pytest.raises(TaskFileError) as err:
        tt.load_task("paper/not_a_task")
    message = str(err.value)
    assert message.startswith("paper/not_a_task: <file>: expected a readable task file or a bundled task name (")
    assert all(name in message for name in bundled_tasks())
