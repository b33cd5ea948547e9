"""Constraint rows that each depend on one interior knot, derived once per family and mapped.

Most rows of the switch NLP (:mod:`tooltransfer.planner.ss.nlp`) read one interior knot only: its
tool centre [mm], its separating variables, the parameters of one body and the knot's margin. A
family of such rows is one small SX function of one knot, ``rows(v, q, m)``, mapped over the ``K``
interior knots (``Function.map``) inside an MX graph. Its Jacobian and the Hessian of
``lam . rows`` are derived once, for one knot, and mapped the same way; their nonzeros are then
placed into the NLP's sparse Jacobian and upper-triangular Lagrangian Hessian
(:func:`placed`).

Why: written out knot by knot in SX, the Lagrangian's Hessian is some 60,000 SX operations, most of
them from the clamped-distance rows' min/max branches. Deriving and storing that expression took
80-130 ms per NLP. Derived for one knot, it is under 1,000 operations, and building the NLP takes a
few milliseconds. The IPOPT callbacks still run compiled SX code, one call per knot; the MX graph
around them holds a few dozen nodes. The rows are the same functions as written knot by knot, so
IPOPT takes the same iterations to rounding (``benchmarks/README.md``, ``bench_ss.py``).

Unit: the NLP's millimetres (:data:`tooltransfer.planner.ss.bodies.UNIT`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray


def placed(local: Any, rows: NDArray[np.intp], cols: NDArray[np.intp], shape: tuple[int, int]) -> Any:
    """The nonzeros of the MX matrix ``local``, in its nonzero order, placed at ``(rows[j], cols[j])``
    of a sparse MX matrix of ``shape`` (the pairs must be distinct)."""
    import casadi as ca

    sp, order = ca.Sparsity.triplet(shape[0], shape[1], [int(r) for r in rows], [int(c) for c in cols], False)
    return ca.MX(sp, ca.vec(local.nz[[int(i) for i in order]]))


@dataclass
class KnotRows:
    """Families of per-knot rows over the ``K`` interior knots of an NLP with ``n_vars`` variables.

    ``var_index`` (K, nv): the NLP variable of each of one knot's ``nv`` variables (increasing along
    each row, so an upper-triangular block stays upper triangular once placed). Families are added
    in row order (:meth:`add`); :meth:`rows`, :meth:`jacobian` and :meth:`hessian` give their part of
    the NLP's constraint vector, Jacobian and Lagrangian Hessian.
    """

    var_index: NDArray[np.intp]
    n_vars: int
    _families: list[tuple[Any, Any, Any, int]] = field(default_factory=list)

    @property
    def n_knots(self) -> int:
        return int(self.var_index.shape[0])

    @property
    def n_rows(self) -> int:
        """Rows of every family added so far."""
        return sum(r for *_, r in self._families) * self.n_knots

    def add(self, name: str, v: Any, q: Any, m: Any, rows: list[Any], q_value: Any, m_value: Any) -> int:
        """Add the family ``rows`` (SX scalars of one knot's variables ``v`` (nv,), its parameters ``q``
        and margin ``m``); in the NLP ``q`` is ``q_value`` (an MX column, the same at every knot) and
        ``m`` the MX row ``m_value`` (1, K). Returns the family's row count (per knot times K)."""
        import casadi as ca

        expr = ca.vertcat(*rows)
        lam = ca.SX.sym("lam", expr.numel())
        fn = ca.Function(name, [v, q, m], [expr])
        jac = ca.Function(f"{name}_jac", [v, q, m], [ca.jacobian(expr, v)])
        hess = ca.Function(f"{name}_hess", [v, q, m, lam], [ca.triu(ca.hessian(ca.dot(lam, expr), v)[0])])
        self._families.append(((fn, jac, hess), q_value, m_value, int(expr.numel())))
        return int(expr.numel()) * self.n_knots

    def _args(self, z: Any, q: Any, m: Any) -> list[Any]:
        import casadi as ca

        K, nv = self.var_index.shape
        V = ca.reshape(z[[int(i) for i in self.var_index.ravel()]], nv, K)
        return [V, ca.repmat(q, 1, K), m]

    def rows(self, z: Any) -> list[Any]:
        """Each family's rows (R K,), knot by knot, at the NLP variables ``z`` (MX)."""
        import casadi as ca

        return [ca.vec(fns[0].map(self.n_knots)(*self._args(z, q, m))) for fns, q, m, _ in self._families]

    def jacobian(self, z: Any, n_rows: int) -> list[Any]:
        """Each family's Jacobian, placed in an ``(n_rows, n_vars)`` sparse MX (rows from 0 in family
        order)."""
        K = self.n_knots
        out, row0 = [], 0
        for (_, jac, _), q, m, R in self._families:
            r, c = (np.asarray(a, dtype=np.intp) for a in jac.sparsity_out(0).get_triplet())
            local = jac.map(K)(*self._args(z, q, m))
            k = np.repeat(np.arange(K), r.size)
            rows = row0 + k * R + np.tile(r, K)
            cols = self.var_index[k, np.tile(c, K)]
            out.append(placed(local, rows, cols, (n_rows, self.n_vars)))
            row0 += R * K
        return out

    def hessian(self, z: Any, lam_g: Any) -> list[Any]:
        """Each family's part of the Lagrangian's Hessian (upper triangle), placed in an
        ``(n_vars, n_vars)`` sparse MX; ``lam_g`` the multipliers of every row (families first)."""
        import casadi as ca

        K = self.n_knots
        out, row0 = [], 0
        for (_, _, hess), q, m, R in self._families:
            r, c = (np.asarray(a, dtype=np.intp) for a in hess.sparsity_out(0).get_triplet())
            lam = ca.reshape(lam_g[row0:row0 + R * K], R, K)
            local = hess.map(K)(*self._args(z, q, m), lam)
            k = np.repeat(np.arange(K), r.size)
            out.append(placed(local, self.var_index[k, np.tile(r, K)], self.var_index[k, np.tile(c, K)],
                              (self.n_vars, self.n_vars)))
            row0 += R * K
        return out
