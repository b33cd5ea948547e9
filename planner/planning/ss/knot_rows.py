"""Constraint rows that each depend on one interior knot, derived once per family and mapped.

Most rows of the switch NLP (:mod:`tooltransfer.planner.planning.ss.nlp`) read one interior knot only: its
tool centre [mm], its separating variables, the parameters of one body and the knot's margin. A
family of such rows is one small SX function of one knot, ``rows(v, q, m)``, mapped over the ``K``
interior knots (``Function.map``) inside an MX graph. Its Jacobian and the Hessian of
``lam . rows`` are derived once, for one knot, and mapped the same way; their nonzeros are then
placed into the NLP's sparse Jacobian and upper-triangular Lagrangian Hessian
(:func:`placed`).

Why: written out knot by knot in SX, the Lagrangian's Hessian is some 60,000 SX operations, most of
them from the clamped-distance rows' min/max branches, slow to derive and store for every NLP.
Derived for one knot, it is under 1,000 operations, and the whole NLP builds several times faster.
IPOPT's callbacks run each family's SX function once per knot in CasADi's virtual
machine; the MX graph around them holds a few dozen nodes. The rows are the same functions as
written knot by knot, and their derivatives equal CasADi's own to rounding: the solves reach the
same outcomes and paths, in the same iterations where a solve is well conditioned (rounding can
change the count of a long or failing one). Figures: ``benchmarks/README.md`` (``bench_ss.py``).

Unit: the NLP's millimetres (:data:`tooltransfer.planner.planning.ss.bodies.UNIT`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray


def triplet(sp: Any) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Rows and columns (each (nnz,)) of the nonzeros of the CasADi sparsity ``sp``, in its nonzero
    order (column by column)."""
    r, c = sp.get_triplet()
    return np.asarray(r, dtype=np.intp), np.asarray(c, dtype=np.intp)


def placed(local: Any, rows: NDArray[np.intp], cols: NDArray[np.intp], shape: tuple[int, int]) -> Any:
    """The nonzeros of the MX matrix ``local``, in its nonzero order, placed at ``(rows[j], cols[j])``
    of a sparse MX matrix of ``shape``.

    Raises:
        ValueError: the pairs are not one per nonzero of ``local``, or two of them coincide (CasADi
            would keep one of the two values and drop the other without a word).
    """
    import casadi as ca

    sp, order = ca.Sparsity.triplet(shape[0], shape[1], [int(r) for r in rows], [int(c) for c in cols], False)
    if not (len(rows) == len(cols) == local.nnz() == len(order)):
        raise ValueError(f"placed: {local.nnz()} nonzeros, {len(rows)} rows and {len(cols)} columns, "
                         f"{len(order)} distinct places")
    return ca.MX(sp, ca.vec(local.nz[[int(i) for i in order]]))


class _Family(NamedTuple):
    """One family of per-knot rows: its functions of one knot (``rows``: (v, q, m) -> rows; ``with_jac``:
    the rows and their Jacobian in ``v``; ``hess``: (v, q, m, lam) -> the upper triangle of the Hessian
    of ``lam . rows``), its parameters in the NLP (``q``, an MX column, the same at every knot; ``m``,
    an MX row (1, K)) and its rows per knot."""

    rows: Any
    with_jac: Any
    hess: Any
    q: Any
    m: Any
    per_knot: int


@dataclass
class KnotRows:
    """Families of per-knot rows over the ``K`` interior knots of an NLP with ``n_vars`` variables.

    ``var_index`` (K, nv): the NLP variable of each of one knot's ``nv`` variables, increasing along
    each row, so that an upper-triangular block stays upper triangular once placed. Families are
    added in row order (:meth:`add`); :meth:`rows`, :meth:`rows_and_jacobian` and :meth:`hessian`
    give their part of the NLP's constraint vector, Jacobian and Lagrangian Hessian.

    Raises:
        ValueError: ``var_index`` is not (K, nv) with rows increasing within ``[0, n_vars)``.
    """

    var_index: NDArray[np.intp]
    n_vars: int
    _families: list[_Family] = field(default_factory=list, init=False, repr=False)

    def __post_init__(self) -> None:
        v = np.asarray(self.var_index)
        if v.ndim != 2 or v.size == 0 or v.min() < 0 or v.max() >= self.n_vars or np.any(np.diff(v, axis=1) <= 0):
            raise ValueError(f"var_index: (K, nv) NLP variables increasing along each row below {self.n_vars}, "
                             f"got shape {v.shape}")

    @property
    def n_knots(self) -> int:
        return int(self.var_index.shape[0])

    def add(self, name: str, v: Any, q: Any, m: Any, rows: list[Any], q_value: Any, m_value: Any) -> int:
        """Add the family ``rows`` (SX scalars of one knot's variables ``v`` (nv,), its parameters ``q``
        and margin ``m``); in the NLP ``q`` is ``q_value`` (an MX column, the same at every knot) and
        ``m`` the MX row ``m_value`` (1, K). Returns the family's row count (per knot times K)."""
        import casadi as ca

        expr = ca.vertcat(*rows)
        lam = ca.SX.sym("lam", expr.numel())
        self._families.append(_Family(
            rows=ca.Function(name, [v, q, m], [expr]),
            with_jac=ca.Function(f"{name}_with_jac", [v, q, m], [expr, ca.jacobian(expr, v)]),
            hess=ca.Function(f"{name}_hess", [v, q, m, lam], [ca.triu(ca.hessian(ca.dot(lam, expr), v)[0])]),
            q=q_value, m=m_value, per_knot=int(expr.numel())))
        return int(expr.numel()) * self.n_knots

    def _knots(self, z: Any) -> Any:
        """The knots' variables (nv, K) of the NLP variables ``z`` (MX), knot k in column k."""
        import casadi as ca

        K, nv = self.var_index.shape
        return ca.reshape(z[[int(i) for i in self.var_index.ravel()]], nv, K)

    def rows(self, z: Any) -> list[Any]:
        """Each family's rows (R K,), knot by knot, at the NLP variables ``z`` (MX)."""
        import casadi as ca

        V = self._knots(z)
        return [ca.vec(f.rows.map(self.n_knots)(V, f.q, f.m)) for f in self._families]

    def rows_and_jacobian(self, z: Any, n_rows: int) -> tuple[list[Any], list[Any]]:
        """Each family's rows (as :meth:`rows`) and its Jacobian, placed in an ``(n_rows, n_vars)``
        sparse MX (rows from 0 in family order), from one mapped call per family."""
        import casadi as ca

        K, V = self.n_knots, self._knots(z)
        values, jacobians, row0 = [], [], 0
        for f in self._families:
            r, c = triplet(f.with_jac.sparsity_out(1))
            g, local = f.with_jac.map(K)(V, f.q, f.m)
            k = np.repeat(np.arange(K), r.size)
            values.append(ca.vec(g))
            jacobians.append(placed(local, row0 + k * f.per_knot + np.tile(r, K), self.var_index[k, np.tile(c, K)],
                                    (n_rows, self.n_vars)))
            row0 += f.per_knot * K
        return values, jacobians

    def hessian(self, z: Any, lam_g: Any) -> list[Any]:
        """Each family's part of the Lagrangian's Hessian (upper triangle), placed in an
        ``(n_vars, n_vars)`` sparse MX; ``lam_g`` the multipliers of every row (families first)."""
        import casadi as ca

        K, V = self.n_knots, self._knots(z)
        out, row0 = [], 0
        for f in self._families:
            r, c = triplet(f.hess.sparsity_out(0))
            lam = ca.reshape(lam_g[row0:row0 + f.per_knot * K], f.per_knot, K)
            local = f.hess.map(K)(V, f.q, f.m, lam)
            k = np.repeat(np.arange(K), r.size)
            out.append(placed(local, self.var_index[k, np.tile(r, K)], self.var_index[k, np.tile(c, K)],
                              (self.n_vars, self.n_vars)))
            row0 += f.per_knot * K
        return out
