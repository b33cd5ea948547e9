"""The compiled core (``_gi_core.c``, built with the package) loaded through ctypes.

It carries the Goldfarb-Idnani steps of :mod:`dmp.qp.dual_active_set` and the residual scan of
:mod:`dmp.qp.pool`. Arrays go in as raw addresses after :func:`addr` checks their dtype and layout
(NumPy's ``ndpointer`` argument checks cost about 7 us per argument and call, which added up to
about 1 ms per fit).
"""

from __future__ import annotations

import ctypes
import importlib.util
from functools import cache
from typing import Any

from numpy.typing import NDArray

PTR = ctypes.c_void_p
PINT = ctypes.POINTER(ctypes.c_int)


@cache
def core() -> ctypes.CDLL:
    """The loaded library with the argument types of every entry point."""
    spec = importlib.util.find_spec("dmp.qp._gi_core")
    if spec is None or spec.origin is None:
        raise ImportError(
            "dmp.qp._gi_core is not built: reinstall tooltransfer with a C compiler (pip install -e .)"
        )
    lib = ctypes.CDLL(spec.origin)
    c_int, c_dbl = ctypes.c_int, ctypes.c_double
    lib.gi_equality.argtypes = [c_int, PTR, PTR, PTR, PINT, PTR, PTR, c_dbl, PTR]
    lib.gi_equality.restype = c_int
    lib.gi_solve.argtypes = [
        c_int, c_int, PTR, PTR, PTR, PTR, PTR, PTR, PINT, c_int, PTR, c_dbl, c_int,
        PINT, PTR, PINT, PINT, PTR,
    ]
    lib.gi_solve.restype = c_int
    lib.gi_warm.argtypes = [c_int, PTR, PTR, PTR, PTR, PTR, PTR, PINT, c_int, PTR, PTR, PTR, c_int, PTR]
    lib.gi_warm.restype = c_int
    c_i64 = ctypes.c_int64
    lib.gi_scan.argtypes = [
        c_int, c_int, c_int, PTR, c_int, c_int, c_int, PTR, PTR, PTR, PTR, PTR, c_dbl, PTR, PTR, PTR, c_int,
        c_i64, c_i64, PTR,
    ]
    lib.gi_scan.restype = c_int
    lib.gi_rows.argtypes = [
        c_int, PTR, PTR, PTR, c_int, c_int, c_int, c_int, c_int, PTR, PTR, PTR, PTR, PTR, PTR, PTR, PTR, PTR, PTR,
        PTR,
    ]
    lib.gi_rows.restype = None
    return lib


def addr(a: NDArray[Any], dtype: type, fortran: bool = False) -> int:
    """Address of ``a``'s data after checking the dtype and layout the C core assumes."""
    ok = a.flags.f_contiguous if fortran else a.flags.c_contiguous
    if a.dtype != dtype or not ok:
        raise TypeError("compiled core: array of unexpected dtype or layout")
    return int(a.ctypes.data)
