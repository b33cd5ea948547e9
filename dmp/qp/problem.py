"""The constrained fit as a domain problem (:class:`FitProblem`) and as a QP (:class:`FitQP`).

Domain problem -> solver problem -> domain result: :class:`FitProblem` says what motion is wanted
(objective terms, constraints, time grid); :func:`build_fit_qp` turns it into matrices on the flat
weights ``w`` that can be inspected, saved, or handed to any QP solver; :func:`tooltransfer.dmp.qp.solve.solve_fit`
returns a :class:`tooltransfer.dmp.qp.result.FitResult` in domain words.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import qpsolvers
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp.affine import AffineRollout
from tooltransfer.dmp.primitive import DMP
from tooltransfer.dmp.qp.constraints.base import Constraint
from tooltransfer.dmp.qp.objectives import Objective, Quadratic
from tooltransfer.errors import InputError
from tooltransfer.validation import check_array, check_positive, check_time


@dataclass
class FitProblem:
    """A constrained DMP fit (docs/design.md section 4).

    Attributes:
        dmp: the primitive whose weights are decided (its parameters fix the basis).
        t: constraint grid, shape (T,) [s]; the motion starts at ``t[0]``.
        x0, g: start and goal (n,) [m]; v0: start velocity (n,) [m/s] (default zero).
        tau: duration [s] (default ``t[-1] - t[0]``).
        objectives: quadratic terms (at least one).
        constraints: constraint objects.
        dense_factor: the true violation is measured on a grid this many times denser (>= 10).
    """

    dmp: DMP
    t: ArrayLike
    x0: ArrayLike
    g: ArrayLike
    objectives: Sequence[Objective]
    constraints: Sequence[Constraint] = ()
    v0: ArrayLike | None = None
    tau: float | None = None
    dense_factor: int = 10
    _aff: dict[str, AffineRollout] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        n = (self.dmp.n_dims,)
        self.t = check_time(self.t, "t", min_len=2)
        self.x0 = check_array(self.x0, "x0", shape=n)
        self.g = check_array(self.g, "g", shape=n)
        self.v0 = np.zeros(n) if self.v0 is None else check_array(self.v0, "v0", shape=n)
        self.tau = float(self.t[-1] - self.t[0]) if self.tau is None else check_positive(self.tau, "tau")
        if not self.objectives:
            raise InputError("objectives", "at least one objective term")
        if not isinstance(self.dense_factor, int) or self.dense_factor < 10:
            raise InputError("dense_factor", "an integer >= 10", repr(self.dense_factor))
        self.objectives = list(self.objectives)
        self.constraints = list(self.constraints)

    @property
    def t_dense(self) -> NDArray[np.float64]:
        """Dense grid (dense_factor*(T-1)+1,) [s] containing every constraint-grid time."""
        t = np.asarray(self.t)
        frac = np.arange(self.dense_factor) / self.dense_factor
        inner = (t[:-1, None] + np.diff(t)[:, None] * frac).ravel()
        return np.append(inner, t[-1])

    def affine(self, which: str = "grid") -> AffineRollout:
        """Affine rollout on the constraint grid (``"grid"``) or the dense grid (``"dense"``)."""
        if which not in self._aff:
            tt = np.asarray(self.t) if which == "grid" else self.t_dense
            self._aff[which] = self.dmp.affine(tt, x0=self.x0, g=self.g, v0=self.v0, tau=self.tau)
        return self._aff[which]

    def quadratic(self) -> Quadratic:
        """Sum of the objective terms on the constraint grid."""
        aff = self.affine("grid")
        terms = [o.quadratic(aff) for o in self.objectives]
        return Quadratic(sum(p for p, _ in terms), sum(q for _, q in terms))  # type: ignore[arg-type]


@dataclass
class FitQP:
    """The fit as matrices on the flat weights: ``min 0.5 w'Pw + q'w, Gw <= h, Aw = b``.

    Rows are the constraints on the constraint grid, linearised along ``x_lin``;
    ``row_family`` / ``eq_family`` name the family of each row.
    """

    P: NDArray[np.float64]
    q: NDArray[np.float64]
    G: NDArray[np.float64]
    h: NDArray[np.float64]
    A: NDArray[np.float64]
    b: NDArray[np.float64]
    row_family: NDArray[np.str_]
    eq_family: NDArray[np.str_]
    x_lin: NDArray[np.float64]
    build_time: float

    def to_qpsolvers(self) -> qpsolvers.Problem:
        """The same QP as a ``qpsolvers.Problem``."""
        return qpsolvers.Problem(self.P, self.q, self.G, self.h, self.A, self.b)

    def save(self, path: str | Path) -> None:
        """Save all matrices and row labels to an ``.npz`` file."""
        np.savez_compressed(
            path,
            P=self.P,
            q=self.q,
            G=self.G,
            h=self.h,
            A=self.A,
            b=self.b,
            row_family=self.row_family,
            eq_family=self.eq_family,
            x_lin=self.x_lin,
        )


def unconstrained_weights(p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Minimiser of ``0.5 w'Pw + q'w`` (least-squares solve, robust to a singular P)."""
    return np.asarray(np.linalg.lstsq(p, -q, rcond=None)[0], dtype=np.float64)


def stack_rows(
    constraints: Sequence[Constraint], aff: AffineRollout, x_lin: NDArray[np.float64]
) -> tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.str_],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.str_],
]:
    """All rows of ``constraints`` on the grid of ``aff``: ``G, h, families, A, b, families``."""
    nw = aff.n_weights
    gs, hs, fs, as_, bs, es = [np.zeros((0, nw))], [np.zeros(0)], [], [np.zeros((0, nw))], [np.zeros(0)], []
    for c in constraints:
        rows = c.coefficients(aff.t, x_lin).all_rows(aff)
        if c.equality:
            as_.append(rows.G)
            bs.append(rows.h)
            es += [c.family] * rows.h.size
        else:
            gs.append(rows.G)
            hs.append(rows.h)
            fs += [c.family] * rows.h.size
    return (
        np.vstack(gs),
        np.concatenate(hs),
        np.array(fs, dtype=str),
        np.vstack(as_),
        np.concatenate(bs),
        np.array(es, dtype=str),
    )


def build_fit_qp(problem: FitProblem, x_lin: ArrayLike | None = None) -> FitQP:
    """Build the condensed QP of ``problem`` on its constraint grid.

    Args:
        x_lin: linearisation path (T, n) [m] for non-convex constraints; default: the
            unconstrained optimum's rollout.
    """
    start = time.perf_counter()
    aff = problem.affine("grid")
    p, q = problem.quadratic()
    if x_lin is None:
        xl = aff.positions(unconstrained_weights(p, q))
    else:
        xl = check_array(x_lin, "x_lin", shape=aff.x_free.shape)
    g, h, fam, a, b, efam = stack_rows(problem.constraints, aff, xl)
    return FitQP(p, q, g, h, a, b, fam, efam, xl, time.perf_counter() - start)
