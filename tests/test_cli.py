"""The demo job runs end to end through the CLI and writes its figure and table."""

from __future__ import annotations

from planner.cli import main


def test_demo_writes_figure_and_table(tmp_path, capsys) -> None:
    assert main(["demo", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "demo.png").stat().st_size > 10_000
    text = (tmp_path / "demo.txt").read_text()
    assert "cone+workspace+obstacle" in text and "solved" in text
