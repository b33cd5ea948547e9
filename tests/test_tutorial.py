"""docs/tutorial.md runs as printed: its python blocks, in order, in one process started in an empty
folder outside the checkout (the bundled task and dataset found through the package), each step's
files where the text says they are."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TUTORIAL = ROOT / "docs" / "tutorial.md"


def _python_blocks() -> list[str]:
    text = TUTORIAL.read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```\n", text, re.DOTALL | re.MULTILINE)


def test_the_tutorial_covers_each_step() -> None:
    text = TUTORIAL.read_text(encoding="utf-8")
    headings = re.findall(r"^## \d\. (\w+)", text, re.MULTILINE)
    assert headings == ["Learn", "Solve", "Look", "Execute", "Choose", "Batch"]
    assert len(_python_blocks()) == len(headings)
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    assert "tutorial.md" in nav


def test_the_tutorial_runs_from_an_empty_folder(tmp_path: Path) -> None:
    """Steps 1-5 in one process, as pasted into a session; step 6 saved as ``batch.py`` and run."""
    pytest.importorskip("mujoco")
    pytest.importorskip("matplotlib")
    *steps, batch = _python_blocks()
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": ""}
    proc = subprocess.run([sys.executable, "-c", "\n".join(steps)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = proc.stdout
    assert "demonstrations of finger" in out and "solved inclined->" in out, out
    assert "open loop: the puck ends" in out, out
    assert "choose: slope solved" in out and "choose: best " in out, out
    for name in ("plan.json", "plan.png", "scene.xml"):
        assert (tmp_path / name).stat().st_size > 0, name
    (tmp_path / "batch.py").write_text(batch, encoding="utf-8")
    proc = subprocess.run([sys.executable, "batch.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600,
                          env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    counts = proc.stdout.splitlines()[0]
    assert counts.startswith("{") and "error" not in counts and "timeout" not in counts, proc.stdout[:2000]
    assert (tmp_path / "report" / "results.csv").is_file()
