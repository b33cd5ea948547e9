"""The tool-library figure is written headless as a PNG."""

from __future__ import annotations

from pathlib import Path

from tooltransfer.planner.apps.plots.tool_library import plot_tool_library


def test_plot_tools_writes_png(tmp_path: Path) -> None:
    out = plot_tool_library(tmp_path / "fig" / "tools.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 50_000
