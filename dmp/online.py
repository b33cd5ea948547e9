r"""Stepwise (online) execution of a DMP with an optional coupling term.

A controller that runs a DMP online advances it one control period at a time and may change what
it pursues between periods: a goal that moves (a puck that is seen again), or a coupling term that
pushes the motion away from an obstacle. With ``z = [x - g, tau * dx/dt]`` per dimension, the
transformation system with a coupling term ``C`` is

$$
\tau^2 \ddot x = \alpha_z(\beta_z(g - x) - \tau \dot x) + f(s) + C, \qquad
\dot z = A z + b\,(f(s(t)) + C),
$$

with ``A = [[0, 1], [-alpha_z*beta_z, -alpha_z]] / tau`` and ``b = [0, 1] / tau``
(:mod:`tooltransfer.dmp.exact`). Over one step of ``dt`` from time ``t`` the goal ``g`` and the
coupling ``C`` are held (zero-order hold, as a controller applies them), so the step is exact:

$$
z(t + dt) = e^{A\,dt} z(t) + \int_0^{dt} e^{A(dt - \sigma)} b\,(f(s(t + \sigma)) + C)\,d\sigma,
$$

the integral by the same Gauss-Legendre rule on the same sub-intervals as the exact rollout
(:func:`tooltransfer.dmp.exact.compute_responses`), so an uncoupled run with a fixed goal reproduces
:meth:`~tooltransfer.dmp.primitive.DMP.rollout` on the same times to round-off, however
the steps are cut. The forcing term ``f = M(x0, g) @ W.T @ psi(s)`` uses the goal of the step, so a
scaled DMP (``scaling`` other than ``"none"``) rescales its shape as the goal moves.

Units: ``x`` [m], ``dx/dt`` [m/s], ``t``, ``dt``, ``tau`` [s]; ``f`` and ``C`` are in the units of
``alpha_z*beta_z*(g - x)``, that is [m] (a coupling ``C`` held constant moves the rest point from
``g`` to ``g + C / (alpha_z*beta_z)``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.basis import basis, phase
from tooltransfer.dmp.exact import _GL_NODES, _GL_WEIGHTS, SystemParams, system_expm
from tooltransfer.dmp.scaling import ScalingMode, scaling_matrix


@dataclass(frozen=True, eq=False)  # array fields: no element-wise __eq__
class DMPState:
    """The state of a DMP run between steps.

    Attributes:
        t: time since the start of the run [s].
        x: position, shape (n,) [m].
        v: velocity ``dx/dt``, shape (n,) [m/s].
        x0: the run's start, shape (n,) [m] (fixes the forcing term's scaling).
        g: the goal in force, shape (n,) [m].
        tau: the run's duration [s].
    """

    t: float
    x: NDArray[np.float64]
    v: NDArray[np.float64]
    x0: NDArray[np.float64]
    g: NDArray[np.float64]
    tau: float


class StepMatrices(NamedTuple):
    """What a step of a given length needs, fixed by the system and the length (cached).

    Attributes:
        n_sub: number of sub-intervals; h: their length [s].
        phi: ``exp(A h)``, shape (2, 2).
        forced: the quadrature of ``exp(A (h - sigma)) b`` times the rule's weights, shape (Q, 2)
            (the forcing term at the Q nodes of a sub-interval enters as ``forced.T @ f``).
        held: the response to a held unit input over one sub-interval, shape (2,).
        nodes: the quadrature nodes' offsets in each sub-interval, shape (n_sub, Q) [s].
    """

    n_sub: int
    h: float
    phi: NDArray[np.float64]
    forced: NDArray[np.float64]
    held: NDArray[np.float64]
    nodes: NDArray[np.float64]


@lru_cache(maxsize=64)
def step_matrices(p: SystemParams, dt: float) -> StepMatrices:
    """The :class:`StepMatrices` of a step of ``dt`` [s]: sub-intervals by the exact rollout's rule
    (none longer than ``tau / (2 max(N, alpha_z, 4))``), then the same Gauss-Legendre rule."""
    h_max = p.tau / (2.0 * max(p.n_basis, p.alpha_z, 4.0))
    n_sub = max(1, int(np.ceil(dt / h_max - 1e-9)))
    h = dt / n_sub
    e = system_expm(p, h * (1.0 - _GL_NODES))[:, :, 1] / p.tau  # (Q, 2)
    forced = (h * _GL_WEIGHTS)[:, None] * e
    nodes = (np.arange(n_sub) * h)[:, None] + h * _GL_NODES
    return StepMatrices(n_sub, h, system_expm(p, np.array(h)), forced, forced.sum(axis=0), nodes)


def exact_step(
    p: SystemParams,
    centres: NDArray[np.float64],
    widths: NDArray[np.float64],
    weights: NDArray[np.float64],
    scaling: ScalingMode,
    state: DMPState,
    dt: float,
    coupling: NDArray[np.float64],
) -> DMPState:
    """Advance ``state`` by ``dt`` [s] with the goal ``state.g`` and ``coupling`` (n,) [m] held.

    ``weights`` (N, n) and the basis ``centres``, ``widths`` (N,) are the DMP's; the result's time is
    ``state.t + dt``.
    """
    sm = step_matrices(p, float(dt))
    wm = weights @ scaling_matrix(scaling, state.x0, state.g).T  # (N, n): psi @ wm is the forcing term
    f = basis(phase(state.t + sm.nodes, p.tau, p.gamma), centres, widths) @ wm  # (n_sub, Q, n)
    held = np.outer(sm.held, coupling)  # (2, n)
    z = np.stack([state.x - state.g, p.tau * state.v])  # (2, n)
    for j in range(sm.n_sub):
        z = sm.phi @ z + sm.forced.T @ f[j] + held
    return DMPState(t=state.t + dt, x=state.g + z[0], v=z[1] / p.tau, x0=state.x0, g=state.g, tau=state.tau)
