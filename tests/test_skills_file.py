"""``tooltransfer learn`` writes one skills file (OE and SS skills); a task can name it instead of a
dataset; damaged or foreign files and a mismatched ``k`` are clear errors (exit code 2)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tooltransfer.planner.apps.cli import main

ROOT = Path(__file__).resolve().parents[1] / "problems"


@pytest.fixture(scope="module")
def skills(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("skills") / "skills.json"
    assert main(["learn", str(ROOT / "data" / "finger_demos"), "-o", str(out)]) == 0
    return out


def task_with(tmp_path: Path, skills: Path, extra: str = "") -> Path:
    text = (ROOT / "paper" / "transfer_tool2.yaml").read_text()
    text = text.replace("skills: {dataset: ../data/finger_demos}", f"skills: {{file: {skills}}}") + extra
    p = tmp_path / "task.yaml"
    p.write_text(text)
    return p


def test_skills_file_holds_both_skills(skills: Path) -> None:
    doc = json.loads(skills.read_text())
    assert doc["format"] == "tooltransfer.skills/1"
    assert doc["oe"]["format"] == "tooltransfer.oe/1" and doc["ss"]["format"] == "tooltransfer.ss/1"
    assert len(doc["dataset_sha256"]) == 64 and len(doc["oe"]["recovered"]) == 8


def test_task_with_skills_file_plans_like_the_dataset(tmp_path: Path, skills: Path, capsys) -> None:
    assert main(["solve", str(task_with(tmp_path, skills)), "--json"]) == 0
    from_file = json.loads(capsys.readouterr().out)
    assert main(["solve", str(ROOT / "paper" / "transfer_tool2.yaml"), "--json"]) == 0
    from_dataset = json.loads(capsys.readouterr().out)
    assert from_file["pushes"] == from_dataset["pushes"]
    assert from_file["switch_clearance_min"] == pytest.approx(from_dataset["switch_clearance_min"], abs=1e-9)


def test_bad_skills_files_exit_2(tmp_path: Path, skills: Path, capsys) -> None:
    damaged = tmp_path / "damaged.json"
    damaged.write_text(skills.read_text()[:500])
    assert main(["solve", str(task_with(tmp_path, damaged))]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    foreign = tmp_path / "foreign.json"
    foreign.write_text(skills.read_text().replace("tooltransfer.skills/1", "tooltransfer.skills/7"))
    assert main(["solve", str(task_with(tmp_path, foreign))]) == 2
    assert "tooltransfer.skills/1" in capsys.readouterr().err
    assert main(["solve", str(task_with(tmp_path, tmp_path / "missing.json"))]) == 2
    assert "skills.file" in capsys.readouterr().err
    assert main(["solve", str(task_with(tmp_path, skills, "oe: {k: 0.3}\n"))]) == 2
    assert "oe.k" in capsys.readouterr().err
