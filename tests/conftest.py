"""Test-wide settings: learned skills are cached in a temporary folder, not in the user's home."""

from __future__ import annotations

import pytest


@pytest.fixture(autouse=True, scope="session")
def _skill_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    mp = pytest.MonkeyPatch()
    mp.setenv("TOOLTRANSFER_CACHE", str(tmp_path_factory.mktemp("skill_cache")))
    yield
    mp.undo()
