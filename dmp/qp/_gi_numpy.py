"""The entry points of ``_gi_core.c`` in NumPy: the fallback when the compiled core is absent
(see :mod:`tooltransfer.dmp.qp.native`).

The same Goldfarb-Idnani steps on the same state (:class:`tooltransfer.dmp.qp.gi_state.GIWork`): the same
choice of row to add (the most violated, the first of equals), the same step lengths, ratio test
and drop rule, the same tolerances and the same infeasibility proof (the rows with negative
``r`` and the row that can be neither reached nor made room for). Only the factorisation updates
differ in their arithmetic: taking a row applies one Householder reflection to the free columns of
``Q`` (the C core applies the equivalent sequence of Givens rotations), dropping one uses SciPy's
Givens update (``scipy.linalg.qr_delete``). Both leave ``N = Q[:, :q] R[:q, :q]`` with ``Q``
orthogonal, and ``d``, ``r`` (the step directions) do not depend on which such factorisation is
kept, so the iterates agree to round-off. The scan and the row builder are the vectorised forms of
``RowPool.residuals`` / ``RowPool.peaks`` and of ``gi_rows``.

Per add/drop step this costs interpreter and call overhead that the compiled core does not pay
(``benchmarks/bench_dmp.py`` measures the whole fit both ways).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg
from numpy.typing import NDArray
from scipy.linalg import blas

from tooltransfer.dmp.qp.gi_state import INFEASIBLE, MAX_ITER, NEED_ROWS, GIWork, PoolArrays

Vec = NDArray[np.float64]
_EMPTY = np.zeros(0)


def _directions(w: GIWork, q: int, np_: Vec) -> tuple[Vec, Vec, Vec]:
    """``qt = Q^T n``, the primal step ``d = Q2 Q2^T n`` and the dual step ``r = R^{-1} qt[:q]``."""
    qt = w.Q.T @ np_
    d = w.Q[:, q:] @ qt[q:]
    r = blas.dtrsv(w.R[:q, :q], qt[:q]) if q else _EMPTY
    return qt, d, r


def _insert(w: GIWork, q: int, qt: Vec) -> None:
    """Append the normal with ``Q^T n = qt`` as column ``q`` of ``R``: a Householder reflection of
    the free columns of ``Q`` maps ``qt[q:]`` to ``|qt[q:]| e_1``."""
    x = qt[q:]
    if x.size > 1:
        sigma2 = float(x[1:] @ x[1:])
        if sigma2 > 0.0:
            x0 = float(x[0])
            alpha = math.sqrt(x0 * x0 + sigma2)
            v = x.copy()
            v[0] = x0 - alpha if x0 <= 0.0 else -sigma2 / (x0 + alpha)  # no cancellation
            beta = 2.0 / (v[0] * v[0] + sigma2)
            qs = w.Q[:, q:]
            blas.dger(-beta, qs @ v, v, a=qs, overwrite_a=1)  # Q2 <- Q2 (I - beta v v^T), in place
            qt[q] = alpha
            qt[q + 1:] = 0.0
    w.R[: q + 1, q] = qt[: q + 1]
    w.R[q + 1:, q] = 0.0
    w.q.value = q + 1


def _delete(w: GIWork, q: int, k: int) -> None:
    """Remove active column ``k`` (``0 <= k < q``), restoring triangularity by Givens rotations."""
    if k == q - 1:
        w.R[:, k] = 0.0
    else:
        q1, r1 = scipy.linalg.qr_delete(w.Q, w.R[:, :q], k, 1, "col", overwrite_qr=True, check_finite=False)
        if not np.shares_memory(q1, w.Q):
            w.Q[...] = q1
        if not np.shares_memory(r1, w.R):
            w.R[:, : q - 1] = r1
        w.R[q:, : q - 1] = 0.0
        w.R[:, q - 1] = 0.0
    w.q.value = q - 1


def _drop(w: GIWork, q: int, k: int) -> None:
    """Drop active inequality ``k``: the factorisation, its multiplier and its candidate index."""
    _delete(w, q, k)
    neq = w.n_eq
    w.u[k: q - 1] = w.u[k + 1: q]
    w.active[k - neq: q - 1 - neq] = w.active[k - neq + 1: q - neq]


class NumpyCore:
    """``gi_equality``, ``gi_solve``, ``gi_warm``, ``gi_scan``, ``gi_rows`` of ``_gi_core.c`` in NumPy."""

    name = "numpy"

    def gi_equality(self, w: GIWork, e: Vec, f: float) -> int:
        q = w.q.value
        qt, d, r = _directions(w, q, e)
        s = float(e @ w.z) - f
        dn = float(d @ e)
        if dn <= 1e-12 * float(e @ e):
            return -1 if abs(s) > 1e-9 else 1
        t = -s / dn
        w.z += t * d
        w.u[:q] -= t * r
        w.u[q] = t
        _insert(w, q, qt)
        return 0

    def gi_solve(self, w: GIWork, g: Vec, h: Vec, tol: float, max_iter: int) -> tuple[int, list[int], bool]:
        neq, z, u, act = w.n_eq, w.z, w.u, w.active
        if h.size == 0:
            return NEED_ROWS, [], False
        while True:
            viol = g @ z - h
            p = int(np.argmax(viol))
            if not viol[p] > tol:
                return NEED_ROWS, [], False
            np_ = -g[p]
            b_p = -float(h[p])
            nn = float(np_ @ np_)
            u_p = 0.0
            while True:
                if w.iters.value >= max_iter:
                    return MAX_ITER, [], False
                w.iters.value += 1
                q = w.q.value
                qt, d, r = _directions(w, q, np_)
                s = float(np_ @ z) - b_p
                t1, k = math.inf, -1
                if q > neq:
                    ri = r[neq:q]
                    pos = ri > 1e-14
                    if pos.any():
                        ratio = np.full(ri.size, math.inf)
                        np.divide(u[neq:q], ri, out=ratio, where=pos)
                        j = int(np.argmin(ratio))
                        t1, k = float(ratio[j]), neq + j
                dn = float(d @ np_)
                t2 = math.inf if dn <= 1e-12 * nn else -s / dn
                if math.isinf(t1) and math.isinf(t2):
                    rows = [int(act[i - neq]) for i in range(neq, q) if r[i] < -1e-14]
                    eq = bool(neq and np.any(np.abs(r[:neq]) > 1e-14))
                    return INFEASIBLE, [*rows, p], eq
                t = t1 if t1 < t2 else t2
                if not math.isinf(t2):
                    z += t * d
                u[:q] -= t * r
                u_p += t
                if t2 <= t1:
                    u[q] = u_p
                    act[q - neq] = p
                    _insert(w, q, qt)
                    break
                _drop(w, q, k)  # the multiplier of active inequality k reached zero

    def gi_warm(self, w: GIWork, g: Vec, h: Vec, rows: NDArray[np.int32]) -> int:
        n, neq, z, u = w.n, w.n_eq, w.z, w.u
        for p in rows.tolist():
            q = w.q.value
            if q >= n:
                break
            np_ = -g[p]
            qt, d, r = _directions(w, q, np_)
            dn = float(d @ np_)
            if dn <= 1e-8 * float(np_ @ np_):
                continue  # nearly dependent: stays a mere candidate (see gi_warm in _gi_core.c)
            t = -(float(np_ @ z) + float(h[p])) / dn
            z += t * d
            u[:q] -= t * r
            u[q] = t
            w.active[q - neq] = p
            _insert(w, q, qt)
        while True:
            q = w.q.value
            ui = u[neq:q]
            if ui.size == 0 or not ui.min() < 0.0:
                return q - neq
            _drop(w, q, neq + int(np.argmin(ui)))
            q -= 1
            # z still meets the remaining rows: their optimum is z_c + Q1 Q1^T (z - z_c), u = R^-1 Q1^T (z - z_c)
            q1 = w.Q[:, :q]
            qt = q1.T @ (z - w.zc)
            z[:] = w.zc + q1 @ qt
            u[:q] = blas.dtrsv(w.R[:q, :q], qt) if q else _EMPTY

    def gi_scan(
        self, pa: PoolArrays, x: Vec, v: Vec, thr: float, res: Vec | None, out_s: NDArray[np.int32],
        out_t: NDArray[np.int64], idx: NDArray[np.int64], start: int, step: int, buf: Vec,
    ) -> int:
        n_l = x.shape[0]
        cols: slice | NDArray[np.int64] = slice(start, start + n_l * step, step) if step > 0 else idx
        r = pa.nb[:, cols].copy() if step > 0 else pa.nb[:, cols]  # fancy indexing copies already
        for a, rows, xv in ((pa.apos, slice(0, pa.npos), x), (pa.avel, slice(pa.vfrom, pa.S), v)):
            if a.shape[0]:
                r[rows] += np.einsum("sdl,ld->sl", a[:, :, cols], xv)
        if res is not None:
            res[...] = r
        peak = r > thr
        if n_l > 1:
            peak[:, 1:] &= r[:, 1:] >= r[:, :-1]
            peak[:, :-1] &= r[:, :-1] >= r[:, 1:]
        s, j = np.nonzero(peak)
        count = s.size
        m = min(count, out_s.size)
        out_s[:m] = s[:m]
        out_t[:m] = start + j[:m] * step if step > 0 else idx[j[:m]]
        return count

    def gi_rows(self, pa: PoolArrays, ids: NDArray[np.int64], g: Vec, h: Vec) -> None:
        if ids.size == 0:
            return
        s, t = pa.series_of[ids], pa.sample_of[ids]
        m, n = ids.size, pa.n
        cp = np.zeros((m, n))
        cv = np.zeros((m, n))
        on = s < pa.npos
        cp[on] = pa.apos[s[on], :, t[on]]
        on = s >= pa.vfrom
        cv[on] = pa.avel[s[on] - pa.vfrom, :, t[on]]
        h[:] = -pa.nb[s, t] - np.einsum("md,md->m", cp, pa.xf[t]) - np.einsum("md,md->m", cv, pa.vf[t])
        cpm, cvm = cp @ pa.M, cv @ pa.M
        rows = pa.Gx[t][:, :, None] * cpm[:, None, :] + pa.Gv[t][:, :, None] * cvm[:, None, :]
        g[...] = rows.reshape(m, pa.N * n)
