"""Constraints on a DMP motion that are linear in the weights (docs/design.md section 4).

A constraint describes, at each sample time, ``m`` rows of the form

    a_pos[k, j] . x(t_k) + a_vel[k, j] . v(t_k)  <=  bound[k, j]      (or ``==`` for equalities)

through :meth:`Constraint.coefficients`. Because the rollout is affine in the weights
(:class:`tooltransfer.dmp.affine.AffineRollout`), each row becomes one linear row ``G w <= h``; the solver only
stacks them. A new constraint type is a new small subclass. Non-convex constraints (a disc to
stay out of) give coefficients that depend on a linearisation trajectory ``x_lin``; evaluated
with ``x_lin = x`` they measure the true violation.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.affine import AffineRollout


class Rows(NamedTuple):
    """Linear rows on the flat weights: ``G @ w <= h`` (or ``==`` for equality constraints).

    Attributes:
        G: shape ``(m, N*n)``.
        h: shape (m,).
    """

    G: NDArray[np.float64]
    h: NDArray[np.float64]


def _apply(a: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a[k] @ x[k]`` for each k: (K, m, n), (K, n) -> (K, m); one matrix product when ``a`` repeats
    one (m, n) block (a broadcast, on which einsum is several times slower)."""
    if a.shape[0] > 1 and a.strides[0] == 0:
        return x @ a[0].T
    return np.einsum("kmd,kd->km", a, x)


@dataclass(frozen=True)
class Coefficients:
    """Per-sample rows of a constraint on samples ``k`` (K,): ``a_pos`` and ``a_vel`` (K, m, n) or
    None, ``bound`` (K, m). Units: ``a`` dimensionless (unit normals where geometric), bound in
    m or m/s, so residuals are in m or m/s."""

    k: NDArray[np.intp]
    a_pos: NDArray[np.float64] | None
    a_vel: NDArray[np.float64] | None
    bound: NDArray[np.float64]

    def residuals(self, x: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
        """Row residuals ``a.x + a.v - bound`` (K, m) for positions/velocities (T, n) on the grid."""
        r = -self.bound
        for a, xv in ((self.a_pos, x), (self.a_vel, v)):
            if a is not None:
                r = r + _apply(a, xv[self.k])
        return r

    def residuals_at(
        self, sel: NDArray[np.intp], x: NDArray[np.float64], v: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Residuals (len(sel), m) of the samples at positions ``sel`` of ``k``, given the positions and
        velocities (len(sel), n) there."""
        r = -self.bound[sel]
        for a, xv in ((self.a_pos, x), (self.a_vel, v)):
            if a is not None:
                r = r + _apply(a[sel], xv)
        return r

    def rows(self, aff: AffineRollout, sel_k: NDArray[np.intp], sel_j: NDArray[np.intp]) -> Rows:
        """Rows ``G w <= h`` for the selected (sample position in ``k``, row) pairs."""
        kk = self.k[sel_k]
        a_pos = None if self.a_pos is None else self.a_pos[sel_k, sel_j]
        a_vel = None if self.a_vel is None else self.a_vel[sel_k, sel_j]
        g, r0 = aff.rows(kk, a_pos, a_vel)
        return Rows(g, self.bound[sel_k, sel_j] - r0)

    def all_rows(self, aff: AffineRollout) -> Rows:
        """Every row of this constraint, sample-major."""
        kk, jj = np.meshgrid(np.arange(self.k.size), np.arange(self.bound.shape[1]), indexing="ij")
        return self.rows(aff, kk.ravel(), jj.ravel())


class Constraint(ABC):
    """Base class. Subclasses set ``family`` and implement :meth:`_coefficients`.

    Args:
        family: name of the constraint family, used in reports and infeasibility messages.
        window: ``(t_start, t_end)`` [s], absolute times where the constraint applies
            (inclusive); None for the whole motion.
    """

    equality: bool = False
    linearised: bool = False
    """True when the rows depend on the linearisation path (non-convex constraint)."""
    conservative: bool = True
    """For linearised constraints: True when rows built on any path imply the true constraint
    (tangent half-planes of a disc), so every iterate is feasible; False when they are exact only
    on the linearisation path itself (the sequential loop then runs until the path settles)."""

    def __init__(self, family: str, window: tuple[float, float] | None = None) -> None:
        self.family = family
        self.window = window

    def samples(self, t: NDArray[np.float64]) -> NDArray[np.intp]:
        """Indices of the samples of ``t`` (T,) [s] where the constraint applies."""
        if self.window is None:
            return np.arange(t.size)
        lo, hi = self.window
        eps = 1e-12 * max(1.0, abs(hi))
        return np.flatnonzero((t >= lo - eps) & (t <= hi + eps))

    def coefficients(self, t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        """Rows at the applicable samples of ``t`` (T,), linearised along ``x_lin`` (T, n) [m]."""
        k = self.samples(t)
        return self._coefficients(k, t, x_lin)

    @abstractmethod
    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        """Rows at samples ``k``."""

    def violation(self, t: NDArray[np.float64], x: NDArray[np.float64], v: NDArray[np.float64]) -> float:
        """True maximum violation [m or m/s] of the motion ``x``, ``v`` (T, n) on times ``t`` (T,).

        Zero when satisfied; for equalities the largest absolute residual.
        """
        c = self.coefficients(t, x)
        if c.k.size == 0:
            return 0.0
        r = c.residuals(x, v)
        return float(np.abs(r).max() if self.equality else max(0.0, r.max()))
