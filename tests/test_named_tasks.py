"""Bundled task files addressable by name (issue 18): ``tooltransfer tasks`` lists them, and ``solve``
takes a name such as ``paper/transfer_tool2`` from any folder."""

from __future__ import annotations

import json
from pathlib import Path

from tooltransfer.planner.apps.cli import main
from tooltransfer.problems.named import bundled_tasks, task_file

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
    assert main(["tasks", "--paths"]) == 0
    assert all(Path(ln.split()[1]).is_file() for ln in capsys.readouterr().out.splitlines())


def test_solve_takes_a_name_from_another_folder(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["solve", "paper/transfer_tool2", "-o", "plan.json", "--json"]) == 0
    assert json.loads((tmp_path / "plan.json").read_text())["status"] == "solved"
    capsys.readouterr()
    assert main(["solve", "paper/not_a_task"]) == 2
    assert "paper/not_a_task" in capsys.readouterr().err
