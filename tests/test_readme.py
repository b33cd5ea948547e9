"""The README's code is tested as printed (issues 17 and 29): every ```python block runs with the project's
Python in a fresh empty folder outside the checkout, as a new user would paste it, and where an ``Output:``
block follows it prints exactly that. ```sh blocks are commands for a shell and are not run here.

Every fenced block is one of: ```python, ```sh, or a bare block right after a line ``Output:`` (what the
python block before it prints), so no block goes untested without saying so. A python block that cannot run
offline or takes long carries the marker :data:`NOT_RUN` with its reason on the line just above its fence,
``<!-- readme-test: not run: REASON -->``; this test then reports it as skipped with that reason.
"""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: The marker above a python block this test does not run (with its reason after the colon).
NOT_RUN = "<!-- readme-test: not run:"
_FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.DOTALL | re.MULTILINE)


@dataclass(frozen=True)
class Block:
    """One fenced block of the README: its language (``""`` for a bare block), its text, the line of its
    opening fence (1-based), what the lines above it say (an ``Output:`` label, a :data:`NOT_RUN` marker)."""

    lang: str
    code: str
    line: int
    is_output: bool
    not_run: str | None


def _blocks() -> list[Block]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = []
    for match in _FENCE.finditer(text):
        above = text[: match.start()].rstrip("\n").rsplit("\n", 1)[-1].strip()
        reason = above[len(NOT_RUN):].removesuffix("-->").strip() if above.startswith(NOT_RUN) else None
        blocks.append(Block(match.group(1), match.group(2), text.count("\n", 0, match.start()) + 1,
                            above == "Output:", reason))
    return blocks


def _python_blocks() -> list[tuple[Block, str | None]]:
    """Each python block with the output the README shows for it (``None`` where it shows none)."""
    blocks = _blocks()
    out = []
    for i, block in enumerate(blocks):
        if block.lang == "python":
            after = blocks[i + 1] if i + 1 < len(blocks) else None
            out.append((block, after.code if after is not None and after.is_output else None))
    return out


def _examples() -> list[tuple[str, str]]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Example\n", 1)[1].split("\n## ", 1)[0]
    pairs = re.findall(r"```python\n(.*?)```\s*\nOutput:\n\n```\n(.*?)```", section, re.DOTALL)
    return pairs


def test_the_example_section_has_its_blocks() -> None:
    pairs = _examples()
    assert len(pairs) == 2
    assert pairs[0][0].startswith("import tooltransfer as tt\n")  # the entry point comes first


def test_every_block_is_python_shell_or_output() -> None:
    blocks = _blocks()
    assert sum(b.lang == "python" for b in blocks) >= 4
    for i, block in enumerate(blocks):
        where = f"README.md line {block.line}"
        if block.lang == "":
            assert block.is_output and blocks[i - 1].lang == "python", f"{where}: a bare block that is no Output"
        else:
            assert block.lang in ("python", "sh"), f"{where}: ```{block.lang} is neither python nor sh"
        assert block.not_run is None or (block.lang == "python" and block.not_run), f"{where}: a bad marker"


@pytest.mark.parametrize("index", range(len(_python_blocks())),
                         ids=[f"line{b.line}" for b, _ in _python_blocks()])
def test_readme_python_block_runs_from_an_empty_folder(index: int, tmp_path: Path) -> None:
    block, shown = _python_blocks()[index]
    if block.not_run is not None:
        pytest.skip(f"README.md line {block.line} is marked not run: {block.not_run}")
    assert ROOT not in tmp_path.resolve().parents  # outside the checkout: nothing found relative to it
    run = subprocess.run([sys.executable, "-c", block.code], cwd=tmp_path, capture_output=True, text=True,
                         timeout=600, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    if shown is not None:
        assert run.stdout == shown
