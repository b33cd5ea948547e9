"""Build-time only (setuptools loads this file, the package never imports it): the compiled dual
active-set core as an optional extension against the stable ABI.

``pyproject.toml`` names the command classes below in ``[tool.setuptools.cmdclass]``, the supported
way to customise setuptools from ``pyproject.toml`` (its ``ext-modules`` table is still
*experimental* and warns at every build, and a ``setup.py`` would sit at the repository's top
level, which the design card fixes). Each command adds the extension to the distribution before
it does its work:

- ``tooltransfer.dmp.qp._gi_core`` from ``dmp/qp/_gi_core.c`` with ``Py_LIMITED_API`` = 3.11 and
  ``py_limited_api``, so the file is ``_gi_core.abi3.so`` and ``bdist_wheel`` tags the wheel
  ``cp311-abi3-<platform>``: one wheel for every CPython >= 3.11 (the library is loaded by ctypes and
  uses no Python API beyond an empty module init, so the stable ABI costs nothing);
- ``optional``: without a working C compiler the build warns and goes on without it, and the
  package falls back to the NumPy core (:mod:`tooltransfer.dmp.qp.native`) at run time.

A free-threaded interpreter (``Py_GIL_DISABLED``, no stable ABI before 3.15) builds the
version-specific file instead.
"""

from __future__ import annotations

import sysconfig
from typing import Any

from setuptools import Extension
from setuptools.command.bdist_wheel import bdist_wheel as _bdist_wheel
from setuptools.command.build import build as _build
from setuptools.command.build_ext import build_ext as _build_ext
from setuptools.command.editable_wheel import editable_wheel as _editable_wheel
from setuptools.command.sdist import sdist as _sdist

LIMITED_API = "cp311"
"""The oldest CPython the stable-ABI build serves (``requires-python``)."""

STABLE_ABI = not sysconfig.get_config_var("Py_GIL_DISABLED")


def core_extension() -> Extension:
    """The compiled core's extension (see the module docstring)."""
    macros = [("Py_LIMITED_API", "0x030B0000")] if STABLE_ABI else []
    return Extension(
        "tooltransfer.dmp.qp._gi_core", sources=["dmp/qp/_gi_core.c"], extra_compile_args=["-O3"], define_macros=macros,
        py_limited_api=STABLE_ABI, optional=True,
    )


def add_core(dist: Any) -> None:
    """Give ``dist`` the compiled core's extension unless it has it already."""
    mods = list(dist.ext_modules or [])
    if not any(getattr(m, "name", None) == "tooltransfer.dmp.qp._gi_core" for m in mods):
        dist.ext_modules = [*mods, core_extension()]


class build(_build):
    def initialize_options(self) -> None:
        add_core(self.distribution)
        super().initialize_options()


class build_ext(_build_ext):
    def initialize_options(self) -> None:
        add_core(self.distribution)
        super().initialize_options()


class sdist(_sdist):
    """Adds the extension so that its C source goes into the source distribution."""

    def initialize_options(self) -> None:
        add_core(self.distribution)
        super().initialize_options()


class editable_wheel(_editable_wheel):
    def initialize_options(self) -> None:
        add_core(self.distribution)
        super().initialize_options()


class bdist_wheel(_bdist_wheel):
    """Tags the wheel for the stable ABI (``cp311-abi3-<platform>``)."""

    def initialize_options(self) -> None:
        add_core(self.distribution)
        super().initialize_options()

    def finalize_options(self) -> None:
        if STABLE_ABI and not getattr(self, "py_limited_api", False):
            self.py_limited_api = LIMITED_API
        super().finalize_options()
