"""The state the dual active-set cores work on: a solve's :class:`GIWork` and a row pool's
:class:`PoolArrays`, with the return codes of ``gi_solve``.

Both cores (the compiled one behind :mod:`tooltransfer.dmp.qp.native` and the NumPy one,
:mod:`tooltransfer.dmp.qp._gi_numpy`) read and write these objects; they live here, below both, so that
neither core imports the other. The arrays are checked against their dimensions once, at creation, and
cannot be rebound afterwards (the compiled core keeps their addresses).
"""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np
from numpy.typing import NDArray

NEED_ROWS, INFEASIBLE, MAX_ITER = 0, -1, -2
"""Return codes of ``gi_solve``."""

F64, I32, I64 = np.dtype(np.float64), np.dtype(np.int32), np.dtype(np.int64)


class _Pinned:
    """Attributes named in ``_pinned`` cannot be rebound once set (the compiled core keeps their
    addresses; in-place updates such as ``w.z += d`` rebind to the same object and are allowed)."""

    _pinned: tuple[str, ...] = ()

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self._pinned and name in self.__dict__ and self.__dict__[name] is not value:
            raise AttributeError(f"{type(self).__name__}.{name} is fixed (the compiled core holds its address)")
        object.__setattr__(self, name, value)


class GIWork(_Pinned):
    """State of one dual active-set solve for ``n`` whitened variables (see ``_gi_core.c``).

    Attributes (the arrays are allocated here with the shapes below and cannot be rebound):
        z: (n,) current point; zc: (n,) the unconstrained optimum ``z_c``.
        Q, R: (n, n) Fortran-ordered; the active normals ``N`` (GI convention ``n . z >= b``)
            satisfy ``N = Q[:, :q] R[:q, :q]``; the first ``n_eq`` are equalities.
        u: (n + 1,) multipliers of the active rows; active: (n + 1,) int32 candidate index of
            active inequality ``i`` at ``active[i]``.
        q, iters: active rows and add/drop steps taken (``ctypes.c_int``, written by either core).
        work: (4n,) scratch; info: (n + 2,) int32 rows of an infeasibility proof.
    """

    _pinned = ("n", "z", "zc", "Q", "R", "u", "active", "q", "iters", "work", "info", "ptr")

    def __init__(self, z_c: NDArray[np.float64]) -> None:
        n = int(np.asarray(z_c).size)
        self.n = n
        self.z = np.array(z_c, dtype=np.float64).ravel()
        self.zc = self.z.copy()
        self.Q = np.asfortranarray(np.eye(n))
        self.R = np.zeros((n, n), order="F")
        self.u = np.zeros(n + 1)
        self.active = np.zeros(n + 1, dtype=np.int32)
        self.q = ctypes.c_int(0)
        self.iters = ctypes.c_int(0)
        self.n_eq = 0
        self.work = np.zeros(4 * n)
        self.info = np.zeros(n + 2, dtype=np.int32)
        _need(self.z, F64, (n,), "z")
        _need(self.zc, F64, (n,), "z_c")
        _need(self.Q, F64, (n, n), "Q", fortran=True)
        _need(self.R, F64, (n, n), "R", fortran=True)
        self.ptr = {k: int(getattr(self, k).ctypes.data) for k in ("z", "zc", "Q", "R", "u", "active", "work", "info")}
        """addresses of the arrays above, for the compiled core."""


class PoolArrays(_Pinned):
    """The arrays of a :class:`tooltransfer.dmp.qp.pool.RowPool` that ``gi_scan`` and ``gi_rows`` read (see
    ``_gi_core.c`` for the layout), with their dimensions, checked here and fixed; refills write
    into them in place (and call :meth:`check_tables`).

    ``S`` series, ``T`` dense samples, ``n`` dimensions, ``N`` basis functions; series
    ``[0, npos)`` have position terms, ``[vfrom, S)`` velocity terms.
    """

    _ARRAYS = ("nb", "apos", "avel", "series_of", "sample_of", "Gx", "Gv", "xf", "vf", "M", "work")
    _pinned = (*_ARRAYS, "S", "T", "n", "N", "npos", "vfrom", "ptr")

    def __init__(
        self, nb: NDArray[np.float64], apos: NDArray[np.float64], avel: NDArray[np.float64],
        series_of: NDArray[np.int64], sample_of: NDArray[np.int64], gx: NDArray[np.float64],
        gv: NDArray[np.float64], xf: NDArray[np.float64], vf: NDArray[np.float64], m: NDArray[np.float64],
        vfrom: int,
    ) -> None:
        self.S, self.T = nb.shape
        self.npos, self.n = apos.shape[0], apos.shape[1]
        self.N = gx.shape[1]
        self.vfrom = int(vfrom)
        self.nb, self.apos, self.avel = nb, apos, avel
        self.series_of, self.sample_of = series_of, sample_of
        self.Gx, self.Gv, self.xf, self.vf, self.M = gx, gv, xf, vf, m
        self.work = np.zeros(4 * self.n)
        S, T, n, N = self.S, self.T, self.n, self.N
        if not (0 <= self.vfrom <= S and 0 <= self.npos <= S):
            raise ValueError("compiled core: series ranges out of bounds")
        _need(nb, F64, (S, T), "nb")
        _need(apos, F64, (self.npos, n, T), "apos")
        _need(avel, F64, (S - self.vfrom, n, T), "avel")
        _need(series_of, I64, series_of.shape, "series_of", ndim=1)
        _need(sample_of, I64, series_of.shape, "sample_of", ndim=1)
        _need(gx, F64, (T, N), "Gx")
        _need(gv, F64, (T, N), "Gv")
        _need(xf, F64, (T, n), "x_free")
        _need(vf, F64, (T, n), "v_free")
        _need(m, F64, (n, n), "M")
        self.check_tables()
        self.ptr = {k: int(getattr(self, k).ctypes.data) for k in self._ARRAYS}
        """addresses of the arrays above, for the compiled core."""

    def check_tables(self) -> None:
        """Raise :class:`ValueError` unless every row id's series and sample are in range."""
        _in_range(self.series_of, 0, self.S, "series of the row ids")
        _in_range(self.sample_of, 0, self.T, "samples of the row ids")


def _need(a: Any, dtype: np.dtype[Any], shape: tuple[int, ...], name: str, fortran: bool = False,
          ndim: int | None = None) -> None:
    """Raise :class:`ValueError` unless ``a`` is an ndarray of ``dtype``, ``shape`` and layout."""
    if not isinstance(a, np.ndarray) or (a.dtype is not dtype and a.dtype != dtype):
        raise ValueError(f"compiled core: {name} must be a {dtype} array")
    if a.shape != shape or (ndim is not None and a.ndim != ndim):
        raise ValueError(f"compiled core: {name} has shape {a.shape}, the dimensions passed need {shape}")
    if not (a.flags.f_contiguous if fortran else a.flags.c_contiguous):
        raise ValueError(f"compiled core: {name} must be {'Fortran' if fortran else 'C'}-contiguous")


def _in_range(a: NDArray[Any], lo: int, hi: int, name: str) -> None:
    if a.size and (int(a.min()) < lo or int(a.max()) >= hi):
        raise ValueError(f"compiled core: {name} out of range [{lo}, {hi})")
