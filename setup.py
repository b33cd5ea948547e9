"""Only the compiled part of the build; everything else is declared in pyproject.toml.

The dual active-set core of the constrained fit (``dmp/qp/dual_active_set.py`` loads it with ctypes).
"""

from setuptools import Extension, setup

setup(ext_modules=[Extension("dmp.qp._gi_core", sources=["dmp/qp/_gi_core.c"], extra_compile_args=["-O3"])])
