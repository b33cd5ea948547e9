"""The dual active-set core: the compiled one (``_gi_core.c``, built with the package, loaded through
ctypes) or, when it is absent, the same steps in NumPy (:mod:`tooltransfer.dmp.qp._gi_numpy`).

Both offer the five entry points of ``_gi_core.c`` with the same semantics: ``gi_equality``,
``gi_solve``, ``gi_warm`` (the Goldfarb-Idnani steps of :mod:`tooltransfer.dmp.qp.dual_active_set`, on a
:class:`~tooltransfer.dmp.qp.gi_state.GIWork`) and ``gi_scan``, ``gi_rows`` (the residual scan and the row builder of
:mod:`tooltransfer.dmp.qp.pool`, on a :class:`PoolArrays`). :func:`core` picks one at first use:

- the compiled core when ``dmp/qp/_gi_core*.so`` (``.pyd`` on Windows) is there and loads;
- the NumPy core, with one :class:`NativeCoreWarning`, when it is not (an install without a C
  compiler, where the build skips the optional extension); the fit reaches the same optimum, more
  slowly (``benchmarks/bench_dmp.py`` measures both);
- the NumPy core, silently, when the environment variable ``TOOLTRANSFER_NO_NATIVE`` is set to
  anything but ``""`` or ``"0"`` (read once, at first use), e.g. to test the fallback.

The compiled core is called with raw addresses. Its wrapper (:class:`CompiledCore`) checks before
every call that each array argument has the dtype, layout and shape the dimensions passed imply,
and that the indices it hands over are in range, so a wrong argument raises :class:`ValueError`
instead of reading or writing out of bounds. The long-lived arrays (a :class:`GIWork`'s
factorisation, a pool's coefficient arrays, :class:`PoolArrays`) carry their dimensions: they are
checked against them once, at creation, cannot be rebound afterwards, and their addresses are
taken then (taking an address and NumPy's ``ndpointer`` checks cost microseconds per argument and
call, which add up over the many calls of one fit).

The library is the extension module ``tooltransfer.dmp.qp._gi_core`` built against the stable ABI (``abi3``,
``Py_LIMITED_API`` 3.11): one file, ``_gi_core.abi3.so``, for every CPython >= 3.11. It carries no
Python API (only an empty module init) and is never imported, only loaded with ctypes.
"""

from __future__ import annotations

import ctypes
import importlib.machinery
import os
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from functools import cache
from pathlib import Path
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.qp.gi_state import (
    F64,
    I32,
    I64,
    INFEASIBLE,
    NEED_ROWS,
    GIWork,
    PoolArrays,
    _in_range,
    _need,
)

ENV_VAR = "TOOLTRANSFER_NO_NATIVE"
"""Set to anything but ``""`` or ``"0"`` to use the NumPy core (read at first use)."""

MODULE = "_gi_core"
"""File name stem of the compiled core in this folder."""

PTR = ctypes.c_void_p
PINT = ctypes.POINTER(ctypes.c_int)


class NativeCoreWarning(UserWarning):
    """The compiled core is absent (or failed to load): the NumPy core is used."""


class Core(Protocol):
    """The entry points of ``_gi_core.c`` (see there for their semantics)."""

    name: str

    def gi_equality(self, w: GIWork, e: NDArray[np.float64], f: float) -> int: ...

    def gi_solve(
        self, w: GIWork, g: NDArray[np.float64], h: NDArray[np.float64], tol: float, max_iter: int
    ) -> tuple[int, list[int], bool]: ...

    def gi_warm(self, w: GIWork, g: NDArray[np.float64], h: NDArray[np.float64], rows: NDArray[np.int32]) -> int: ...

    def gi_scan(
        self, pa: PoolArrays, x: NDArray[np.float64], v: NDArray[np.float64], thr: float,
        res: NDArray[np.float64] | None, out_s: NDArray[np.int32], out_t: NDArray[np.int64],
        idx: NDArray[np.int64], start: int, step: int, buf: NDArray[np.float64],
    ) -> int: ...

    def gi_rows(
        self, pa: PoolArrays, ids: NDArray[np.int64], g: NDArray[np.float64], h: NDArray[np.float64]
    ) -> None: ...


def _check_work(w: GIWork) -> dict[str, int]:
    """The state's addresses, after checking its active-row counts (its arrays are fixed at creation)."""
    if not (0 <= w.n_eq <= w.q.value <= w.n):
        raise ValueError(f"compiled core: {w.q.value} active rows ({w.n_eq} equalities) for {w.n} variables")
    return w.ptr


def _rows_arg(w: GIWork, g: NDArray[np.float64], h: NDArray[np.float64]) -> int:
    m = h.shape[0] if h.ndim == 1 else -1
    _need(h, F64, (m,), "h")
    _need(g, F64, (m, w.n), "G")
    return m


class CompiledCore:
    """The compiled core, every entry point behind argument checks."""

    name = "compiled"

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = str(path)
        lib = ctypes.CDLL(self.path)
        c_int, c_dbl, c_i64 = ctypes.c_int, ctypes.c_double, ctypes.c_int64
        lib.gi_equality.argtypes = [c_int, PTR, PTR, PTR, PINT, PTR, PTR, c_dbl, PTR]
        lib.gi_equality.restype = c_int
        lib.gi_solve.argtypes = [
            c_int, c_int, PTR, PTR, PTR, PTR, PTR, PTR, PINT, c_int, PTR, c_dbl, c_int,
            PINT, PTR, PINT, PINT, PTR,
        ]
        lib.gi_solve.restype = c_int
        lib.gi_warm.argtypes = [c_int, PTR, PTR, PTR, PTR, PTR, PTR, PINT, c_int, PTR, PTR, PTR, c_int, PTR]
        lib.gi_warm.restype = c_int
        lib.gi_scan.argtypes = [
            c_int, c_int, c_int, PTR, c_int, c_int, c_int, PTR, PTR, PTR, PTR, PTR, c_dbl, PTR, PTR, PTR, c_int,
            c_i64, c_i64, PTR,
        ]
        lib.gi_scan.restype = c_int
        lib.gi_rows.argtypes = [
            c_int, PTR, PTR, PTR, c_int, c_int, c_int, c_int, c_int, PTR, PTR, PTR, PTR, PTR, PTR, PTR, PTR, PTR,
            PTR, PTR,
        ]
        lib.gi_rows.restype = None
        self.lib = lib

    def gi_equality(self, w: GIWork, e: NDArray[np.float64], f: float) -> int:
        p = _check_work(w)
        _need(e, F64, (w.n,), "e")
        return int(self.lib.gi_equality(w.n, p["Q"], p["R"], p["u"], ctypes.byref(w.q), p["z"],
                                        int(e.ctypes.data), float(f), p["work"]))

    def gi_solve(
        self, w: GIWork, g: NDArray[np.float64], h: NDArray[np.float64], tol: float, max_iter: int
    ) -> tuple[int, list[int], bool]:
        p = _check_work(w)
        m = _rows_arg(w, g, h)
        if m == 0:
            return NEED_ROWS, [], False
        ninfo, eq = ctypes.c_int(0), ctypes.c_int(0)
        code = self.lib.gi_solve(
            w.n, m, int(g.ctypes.data), int(h.ctypes.data), p["Q"], p["R"], p["u"], p["active"], ctypes.byref(w.q),
            w.n_eq, p["z"], float(tol), int(max_iter), ctypes.byref(w.iters), p["info"], ctypes.byref(ninfo),
            ctypes.byref(eq), p["work"],
        )
        if code == INFEASIBLE:
            return code, w.info[: ninfo.value].tolist(), bool(eq.value)
        return int(code), [], False

    def gi_warm(self, w: GIWork, g: NDArray[np.float64], h: NDArray[np.float64], rows: NDArray[np.int32]) -> int:
        p = _check_work(w)
        m = _rows_arg(w, g, h)
        _need(rows, I32, (rows.size,), "rows", ndim=1)
        _in_range(rows, 0, m, "warm-start rows")
        return int(self.lib.gi_warm(
            w.n, int(g.ctypes.data), int(h.ctypes.data), p["Q"], p["R"], p["u"], p["active"], ctypes.byref(w.q),
            w.n_eq, p["z"], p["zc"], int(rows.ctypes.data), rows.size, p["work"],
        ))

    def gi_scan(
        self, pa: PoolArrays, x: NDArray[np.float64], v: NDArray[np.float64], thr: float,
        res: NDArray[np.float64] | None, out_s: NDArray[np.int32], out_t: NDArray[np.int64],
        idx: NDArray[np.int64], start: int, step: int, buf: NDArray[np.float64],
    ) -> int:
        p = pa.ptr
        L = x.shape[0] if x.ndim == 2 else -1
        _need(x, F64, (L, pa.n), "x")
        _need(v, F64, (L, pa.n), "v")
        if step > 0:
            if not (0 <= start and (L == 0 or start + (L - 1) * step < pa.T)):
                raise ValueError("compiled core: sample slice out of range")
        else:
            _need(idx, I64, (L,), "idx")
            _in_range(idx, 0, pa.T, "sample indices")
        if res is not None:
            _need(res, F64, (pa.S, L), "res")
        cap = out_s.shape[0] if out_s.ndim == 1 else -1
        _need(out_s, I32, (cap,), "out_s")
        _need(out_t, I64, (cap,), "out_t")
        if buf.ndim != 1 or buf.shape[0] < L:
            raise ValueError("compiled core: buf shorter than the samples")
        _need(buf, F64, buf.shape, "buf")
        res_p = None if res is None else int(res.ctypes.data)
        return int(self.lib.gi_scan(
            pa.S, pa.T, L, int(idx.ctypes.data) if step <= 0 else None, pa.n, pa.npos, pa.vfrom, p["nb"], p["apos"],
            p["avel"], int(x.ctypes.data), int(v.ctypes.data), float(thr), res_p, int(out_s.ctypes.data),
            int(out_t.ctypes.data), cap, int(start), int(step) if step > 0 else 0, int(buf.ctypes.data),
        ))

    def gi_rows(self, pa: PoolArrays, ids: NDArray[np.int64], g: NDArray[np.float64], h: NDArray[np.float64]) -> None:
        p = pa.ptr
        m = ids.shape[0] if ids.ndim == 1 else -1
        _need(ids, I64, (m,), "ids")
        _need(g, F64, (m, pa.N * pa.n), "G")
        _need(h, F64, (m,), "h")
        if m == 0:
            return
        _in_range(ids, 0, pa.series_of.size, "row ids")
        self.lib.gi_rows(
            m, int(ids.ctypes.data), p["series_of"], p["sample_of"], pa.T, pa.n, pa.N, pa.npos, pa.vfrom, p["nb"],
            p["apos"], p["avel"], p["Gx"], p["Gv"], p["xf"], p["vf"], p["M"], int(g.ctypes.data), int(h.ctypes.data),
            p["work"],
        )


def compiled_path() -> Path | None:
    """The compiled core's file in this folder (``_gi_core`` with an extension-module suffix this
    interpreter accepts, e.g. ``.abi3.so``), or None; the newest when there are several (a build
    left over from before, such as ``_gi_core.cpython-311-x86_64-linux-gnu.so``, never shadows a
    newer one)."""
    here = Path(__file__).resolve().parent
    found = [p for suffix in importlib.machinery.EXTENSION_SUFFIXES if (p := here / f"{MODULE}{suffix}").is_file()]
    return max(found, key=lambda p: p.stat().st_mtime) if found else None


def disabled_by_env() -> bool:
    """Whether ``TOOLTRANSFER_NO_NATIVE`` asks for the NumPy core."""
    return os.environ.get(ENV_VAR, "").strip() not in ("", "0")


@cache
def _compiled_core(path: Path) -> CompiledCore:
    return CompiledCore(path)


def _numpy_core() -> Core:
    from tooltransfer.dmp.qp._gi_numpy import NumpyCore

    return NumpyCore()


_PACKAGE_DIR = str(Path(__file__).resolve().parents[1]) + os.sep


@cache
def default_core() -> Core:
    """The core :func:`core` returns unless overridden (chosen at the first call; see the module docstring)."""
    if disabled_by_env():
        return _numpy_core()
    path = compiled_path()
    why = "is not built"
    if path is not None:
        try:
            return _compiled_core(path)
        except (OSError, AttributeError) as exc:
            why = f"failed to load ({exc})"
    level, f = 1, sys._getframe()  # point the warning at the first caller outside the dmp package
    while f.f_code.co_filename.startswith(_PACKAGE_DIR) and f.f_back is not None:
        f, level = f.f_back, level + 1
    warnings.warn(
        f"tooltransfer: the compiled dual active-set core (dmp/qp/{MODULE}) {why}; using the NumPy core "
        "(the same optimum, slower fits; reinstall with a C compiler for the fast path)",
        NativeCoreWarning, stacklevel=level,
    )
    return _numpy_core()


_override: ContextVar[Core | None] = ContextVar("tooltransfer_gi_core", default=None)


def core() -> Core:
    """The core in use: :func:`default_core`, or the innermost :func:`using` (of this thread or task)."""
    c = _override.get()
    return default_core() if c is None else c


@contextmanager
def using(which: str | Core) -> Iterator[Core]:
    """Use ``which`` (``"compiled"``, ``"numpy"`` or a core) for the solvers created inside the block
    (in this thread or asyncio task; for tests and benchmarks)."""
    if isinstance(which, str):
        if which == "numpy":
            c = _numpy_core()
        elif which == "compiled":
            path = compiled_path()
            if path is None:
                raise ImportError(f"tooltransfer.dmp.qp.{MODULE} is not built: reinstall tooltransfer with a C "
                                  "compiler")
            c = _compiled_core(path)
        else:
            raise ValueError(f"unknown core {which!r}: 'compiled' or 'numpy'")
    else:
        c = which
    token = _override.set(c)
    try:
        yield c
    finally:
        _override.reset(token)
