"""The README's examples are tests (issue 17): every ```python block of its "Example" section runs, from
the repository's root as the README assumes, and prints exactly the ``Output:`` block below it."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _examples() -> list[tuple[str, str]]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Example\n", 1)[1].split("\n## ", 1)[0]
    pairs = re.findall(r"```python\n(.*?)```\s*\nOutput:\n\n```\n(.*?)```", section, re.DOTALL)
    return pairs


def test_the_example_section_has_its_blocks() -> None:
    pairs = _examples()
    assert len(pairs) == 2
    assert pairs[0][0].startswith("import tooltransfer as tt\n")  # the entry point comes first


@pytest.mark.parametrize("index", range(2))
def test_readme_example_prints_what_the_readme_shows(index: int) -> None:
    code, shown = _examples()[index]
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=600,
                         check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout == shown
