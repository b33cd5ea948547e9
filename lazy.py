"""Names a package exports from its submodules, imported on first use (PEP 562).

A package's ``__init__`` maps each name it exports to the submodule it lives in, and its module
``__getattr__`` calls :func:`lazy_attribute`: the submodule is imported when the name is first asked
for and the value kept in the package. A command that needs one corner of a package then does not pay
for the rest (the command line's quick commands start in a fraction of a second).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from importlib import import_module
from typing import Any


def lazy_attribute(package: str, homes: Mapping[str, str], name: str) -> Any:
    """The attribute ``name`` of the package named ``package``, imported from its submodule
    ``homes[name]`` (relative to the package) and bound in the package for the next use.

    Raises:
        AttributeError: ``name`` is not one of ``homes`` (as for any missing module attribute).
    """
    if name not in homes:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    value = getattr(import_module(f"{package}.{homes[name]}"), name)
    vars(sys.modules[package])[name] = value  # the module's dict: no __setattr__ of the package runs
    return value
