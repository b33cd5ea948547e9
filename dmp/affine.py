"""Rollout as an affine map of the weights, on one time grid (docs/design.md section 3).

With ``w = W.ravel()`` (W of shape (N, n), row-major so ``w[i*n + e] = W[i, e]``), positions and
velocities at the samples are ``x(t_k) = x_free[k] + M @ W.T @ Gx[k]`` and likewise with ``Gv``,
so any linear function ``a . x(t_k)`` of the motion is a linear function of ``w``:
``a . x(t_k) = a . x_free[k] + kron(Gx[k], M.T @ a) @ w``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class AffineRollout:
    """Affine maps from weights to sampled positions and velocities.

    Attributes:
        t: absolute sample times, shape (T,) [s].
        x_free: unforced positions [m], shape (T, n).
        v_free: unforced velocities [m/s], shape (T, n).
        Gx: position responses to each basis function, shape (T, N) (see :mod:`tooltransfer.dmp.exact`).
        Gv: velocity responses to each basis function, shape (T, N).
        M: forcing-term scaling matrix, shape (n, n).
        psi: basis values at the samples, shape (T, N).
    """

    t: NDArray[np.float64]
    x_free: NDArray[np.float64]
    v_free: NDArray[np.float64]
    Gx: NDArray[np.float64]
    Gv: NDArray[np.float64]
    M: NDArray[np.float64]
    psi: NDArray[np.float64]

    @property
    def n_dims(self) -> int:
        return int(self.M.shape[0])

    @property
    def n_weights(self) -> int:
        return int(self.Gx.shape[1] * self.M.shape[0])

    def _apply(
        self, base: NDArray[np.float64], resp: NDArray[np.float64], w: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        wmat = np.asarray(w, dtype=np.float64).reshape(self.Gx.shape[1], self.n_dims)
        return base + resp @ wmat @ self.M.T

    def positions(self, w: NDArray[np.float64]) -> NDArray[np.float64]:
        """Positions (T, n) [m] for flat weights ``w``, shape ``(N*n,)``."""
        return self._apply(self.x_free, self.Gx, w)

    def velocities(self, w: NDArray[np.float64]) -> NDArray[np.float64]:
        """Velocities (T, n) [m/s] for flat weights ``w``, shape ``(N*n,)``."""
        return self._apply(self.v_free, self.Gv, w)

    def position_matrix(self) -> NDArray[np.float64]:
        """``D`` of shape ``(T*n, N*n)`` with ``positions(w).ravel() = x_free.ravel() + D @ w``."""
        return np.asarray(np.kron(self.Gx, self.M), dtype=np.float64)

    def rows(
        self,
        k: NDArray[np.intp],
        a_pos: NDArray[np.float64] | None,
        a_vel: NDArray[np.float64] | None,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Linear functions ``a_pos[j] . x(t_k[j]) + a_vel[j] . v(t_k[j])`` as ``(R @ w + r0)``.

        Args:
            k: sample indices, shape (m,).
            a_pos, a_vel: coefficient vectors, shape (m, n), or None for zero.
        Returns:
            ``R`` of shape ``(m, N*n)`` and ``r0`` of shape (m,).
        """
        m = k.size
        n_b = self.Gx.shape[1]
        rows = np.zeros((m, n_b, self.n_dims))
        r0 = np.zeros(m)
        if a_pos is not None:
            rows += self.Gx[k][:, :, None] * (a_pos @ self.M)[:, None, :]
            r0 += np.einsum("jd,jd->j", a_pos, self.x_free[k])
        if a_vel is not None:
            rows += self.Gv[k][:, :, None] * (a_vel @ self.M)[:, None, :]
            r0 += np.einsum("jd,jd->j", a_vel, self.v_free[k])
        return rows.reshape(m, n_b * self.n_dims), r0
