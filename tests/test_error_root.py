"""One error root (issue 17): every exception class the package defines (warnings aside) derives from
:class:`tooltransfer.errors.ToolTransferError`, the root the CLI catches, and the root lives in the
bottom layer (``tooltransfer.errors``), not in a subpackage."""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

from tooltransfer.errors import ToolTransferError

ROOT = Path(__file__).resolve().parents[1]


def _module_names() -> list[str]:
    names = []
    for path in [*ROOT.glob("*.py"), *(p for top in ("dmp", "tools", "problems", "planner")
                                       for p in (ROOT / top).rglob("*.py"))]:
        parts = path.relative_to(ROOT).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if parts and parts[-1] == "_build":  # build-time only (setuptools loads it)
            continue
        names.append(".".join(("tooltransfer", *parts)))
    return sorted(names)


def test_every_exception_of_the_package_derives_from_the_root() -> None:
    names = _module_names()
    assert len(names) > 150
    outside = []
    for name in names:
        module = importlib.import_module(name)
        for cls_name, cls in inspect.getmembers(module, inspect.isclass):
            if cls.__module__ == name and issubclass(cls, BaseException) and not issubclass(cls, Warning) \
                    and not issubclass(cls, ToolTransferError):
                outside.append(f"{name}.{cls_name}")
    assert outside == []
    assert ToolTransferError.__module__ == "tooltransfer.errors"
