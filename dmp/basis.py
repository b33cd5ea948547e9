"""Canonical system and basis functions of the forcing term (paper eqs. 2-3).

Notation (shared by the whole package):

- ``s``: phase, ``tau * ds/dt = -gamma * s``, so ``s(t) = exp(-gamma * (t - t0) / tau)``.
- ``phi_i(s) = exp(-h_i * (s - c_i)**2)``: Gaussian kernels with centres ``c_i`` spaced evenly in
  time (``c_i = exp(-gamma * i / (N - 1))``) and widths ``h_i`` from the neighbour spacing.
- ``psi_i(s) = phi_i(s) * s / sum_j phi_j(s)``: normalised, phase-gated basis (eq. 3), so the
  forcing term ``f(s) = sum_i w_i psi_i(s)`` vanishes as ``s -> 0``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

DEFAULT_GAMMA = float(-np.log(0.01))
"""Phase constant that brings the phase to 0.01 at ``t = tau``."""


def centres_and_widths(n_basis: int, gamma: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return kernel centres ``c`` (N,) in phase units and widths ``h`` (N,) [1/phase^2].

    Centres are evenly spaced in time over ``[0, tau]``; ``h_i = 1 / (c_{i+1} - c_i)^2`` (the last
    width repeats its neighbour's), which gives the usual overlap of neighbouring kernels.
    """
    if n_basis == 1:
        return np.array([1.0]), np.array([1.0])
    c = np.exp(-gamma * np.linspace(0.0, 1.0, n_basis))
    h = np.empty(n_basis)
    h[:-1] = 1.0 / np.diff(c) ** 2
    h[-1] = h[-2]
    return c, h


def phase(t: NDArray[np.float64], tau: float, gamma: float) -> NDArray[np.float64]:
    """Phase ``s(t) = exp(-gamma * t / tau)`` for times ``t`` [s] measured from the start."""
    return np.exp(-gamma * np.asarray(t, dtype=np.float64) / tau)


def basis(s: NDArray[np.float64], c: NDArray[np.float64], h: NDArray[np.float64]) -> NDArray[np.float64]:
    """Normalised basis ``psi(s)`` of shape ``s.shape + (N,)`` (eq. 3).

    The normalisation is computed in log space, so it never divides by an underflowed sum.
    """
    s = np.asarray(s, dtype=np.float64)
    logphi = -h * (s[..., None] - c) ** 2
    logphi -= logphi.max(axis=-1, keepdims=True)
    phi = np.exp(logphi)
    return phi * (s[..., None] / phi.sum(axis=-1, keepdims=True))
