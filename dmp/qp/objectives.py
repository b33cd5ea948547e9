"""Quadratic objectives of the constrained DMP fit: each emits ``(P, q)`` on the flat weights.

The objective is ``sum_terms 0.5 w^T P w + q^T w`` (constants dropped). Terms are averaged over
samples so weights are comparable between grids.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp.affine import AffineRollout
from tooltransfer.errors import InputError
from tooltransfer.validation import check_array, check_positive


class Quadratic(NamedTuple):
    """``0.5 w^T P w + q^T w``; ``P`` of shape ``(N*n, N*n)``, ``q`` of shape ``(N*n,)``."""

    P: NDArray[np.float64]
    q: NDArray[np.float64]


class Objective(ABC):
    """A quadratic term built on the constraint grid's affine rollout."""

    @abstractmethod
    def quadratic(self, aff: AffineRollout) -> Quadratic:
        """The term's ``(P, q)``."""


class TrackPath(Objective):
    """Trajectory-space tracking: ``weight/T * 0.5 * sum_k |x(t_k) - ref_k|^2``.

    Args:
        reference: positions (T, n) [m] on the constraint grid.
    """

    def __init__(self, reference: ArrayLike, weight: float = 1.0) -> None:
        self.reference = check_array(reference, "reference", ndim=2)
        self.weight = check_positive(weight, "weight")

    def quadratic(self, aff: AffineRollout) -> Quadratic:
        if self.reference.shape != aff.x_free.shape:
            raise InputError("reference", f"shape {aff.x_free.shape} (the constraint grid)", f"{self.reference.shape}")
        s = self.weight / aff.t.size
        p = s * np.kron(aff.Gx.T @ aff.Gx, aff.M.T @ aff.M)
        q = s * (aff.Gx.T @ (aff.x_free - self.reference) @ aff.M).ravel()
        return Quadratic(np.asarray(p, dtype=np.float64), np.asarray(q, dtype=np.float64))


class MatchForcing(Objective):
    """Forcing-space regression (eq. 4): ``weight/T * 0.5 * sum_k |f(t_k) - target_k|^2``.

    Args:
        target: forcing values (T, n) on the constraint grid, e.g. from :meth:`from_path`.
    """

    def __init__(self, target: ArrayLike, weight: float = 1.0) -> None:
        self.target = check_array(target, "target", ndim=2)
        self.weight = check_positive(weight, "weight")

    @classmethod
    def from_path(
        cls, t: ArrayLike, path: ArrayLike, alpha_z: float, beta_z: float, tau: float, weight: float = 1.0
    ) -> MatchForcing:
        """Forcing targets ``tau^2 xdd - alpha_z (beta_z (g - x) - tau xd)`` of a path (T, n) [m]
        on times ``t`` (T,) [s], goal = the path's end, derivatives by finite differences."""
        tt = check_array(t, "t", ndim=1)
        x = check_array(path, "path", shape=(tt.size, None))
        xd = np.gradient(x, tt, axis=0, edge_order=2)
        xdd = np.gradient(xd, tt, axis=0, edge_order=2)
        return cls(tau**2 * xdd - alpha_z * (beta_z * (x[-1] - x) - tau * xd), weight)

    def quadratic(self, aff: AffineRollout) -> Quadratic:
        if self.target.shape != aff.x_free.shape:
            raise InputError("target", f"shape {aff.x_free.shape} (the constraint grid)", f"{self.target.shape}")
        s = self.weight / aff.t.size
        p = s * np.kron(aff.psi.T @ aff.psi, aff.M.T @ aff.M)
        q = -s * (aff.psi.T @ self.target @ aff.M).ravel()
        return Quadratic(np.asarray(p, dtype=np.float64), np.asarray(q, dtype=np.float64))


class Ridge(Objective):
    """``weight * 0.5 * |w - w_ref|^2`` (regularisation towards reference weights, default 0)."""

    def __init__(self, weight: float, w_ref: ArrayLike | None = None) -> None:
        self.weight = check_positive(weight, "weight")
        self.w_ref = None if w_ref is None else check_array(w_ref, "w_ref").ravel()

    def quadratic(self, aff: AffineRollout) -> Quadratic:
        n = aff.n_weights
        q = np.zeros(n) if self.w_ref is None else -self.weight * self.w_ref
        if q.size != n:
            raise InputError("w_ref", f"{n} weights", f"{q.size}")
        return Quadratic(self.weight * np.eye(n), q)
