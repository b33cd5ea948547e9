"""The tool-library figure script runs headless and writes a PNG."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_plot_tools_writes_png(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("plot_tools", ROOT / "examples" / "plot_tools.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    out = tmp_path / "fig" / "tools.png"
    module.main([str(out)])
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 50_000
