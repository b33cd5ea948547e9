"""The demo job runs end to end through the CLI and writes its figure and table."""

from __future__ import annotations

from planner.cli import main


def test_demo_runs_the_transfer_job(tmp_path, capsys) -> None:
    assert main(["demo", "--out", str(tmp_path)]) == 0
    for name in ("fig8a_demonstrations.png", "fig8b_universal_skill.png", "fig10_condensed_paths.png",
                 "fig14_safety_margin.png", "plan_transfer_tool2_qp.json", "plan_transfer_tool2_mapping.json"):
        assert (tmp_path / name).stat().st_size > 1_000, name
    text = (tmp_path / "report.txt").read_text()
    assert "simulated qp plan" in text and "solved" in text


def test_schema_command_prints_the_task_schema(capsys) -> None:
    import json

    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema["title"] == "Task" and "start" in schema["required"]


def test_tools_command_writes_the_library_figure(tmp_path) -> None:
    out = tmp_path / "tools.png"
    assert main(["tools", "--out", str(out)]) == 0
    assert out.stat().st_size > 50_000


def test_bad_usage_exits_2(capsys) -> None:
    import pytest

    with pytest.raises(SystemExit) as exc:
        main(["solve-everything"])
    assert exc.value.code == 2
    assert "invalid choice" in capsys.readouterr().err
