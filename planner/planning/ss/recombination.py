"""Recombination (eq. 18) as one linear map per time grid, for the ``dmp`` variant's speed.

With the forcing-term scaling ``"none"`` (``M = I``, as the paper and the SS skill use) every step of
:func:`tooltransfer.planner.planning.ss.dmp_variant.recombine` between the new virtual motion and the rolled-out path is
linear:

* fitting ``f^o`` to the virtual motion ``x^o - x_o`` (T, 2) on the grid ``t`` (T,) is a linear map
  ``W^o = L (x^o - x_o)`` (:meth:`tooltransfer.dmp.primitive.DMP.fit`: numerical derivatives, forcing targets with
  the goal ``x^o(T)``, ridge least squares whose regularisation depends on the basis only);
* the rollout from ``x0 = 0``, ``v0 = 0`` towards ``g`` with weights ``W`` is
  ``x = a g^T + Gx W`` (:mod:`tooltransfer.dmp.exact`: ``a`` (T,) the unforced response to a unit goal).

So ``x = a g^T + Gx (k1 * W^t) + (Gx L) (x^o - x_o)``. :class:`RecombinationMap` holds ``a``, ``Gx``
and ``Gx L`` for one (DMP settings, grid); ``L`` is obtained by probing ``DMP.fit`` itself with unit
paths (the map is the library's fit, not a re-implementation; the tests compare both routes).
Maps are cached per (settings, grid) (:func:`recombination_map`).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.primitive import DMP


@dataclass(frozen=True)
class RecombinationMap:
    """Linear maps of one grid (module docstring).

    Attributes:
        t: the grid (T,) [s] from 0.
        a: shape (T,), unforced rollout towards a unit goal from rest at 0.
        Gx: shape (T, N), position responses to the basis weights.
        GL: shape (T, T), ``Gx L``: virtual motion (relative) -> its forcing term's contribution.
    """

    t: NDArray[np.float64]
    a: NDArray[np.float64]
    Gx: NDArray[np.float64]
    GL: NDArray[np.float64]

    def path(self, w_tool: NDArray[np.float64], x_virtual: NDArray[np.float64],
             g: NDArray[np.float64]) -> NDArray[np.float64]:
        """Rolled-out path (T, 2) [m] relative to ``x_o`` for the scaled pure tool weights ``w_tool``
        (N, 2) (``k1 * W^t``), the virtual motion ``x_virtual`` (T, 2) relative to ``x_o`` and the
        goal ``g`` (2,): eq. (18) then the rollout."""
        return self.a[:, None] * g[None, :] + self.Gx @ w_tool + self.GL @ x_virtual


def dmp_settings(d: DMP) -> tuple:
    """What the maps depend on: dimensions, basis count, gains, phase constant, scaling, ridge."""
    return (d.n_dims, d.n_basis, d.alpha_z, d.beta_z, d.gamma, d.scaling, d.ridge)


_CACHE: OrderedDict[tuple, RecombinationMap] = OrderedDict()
_MAXSIZE = 32


def linear_recombination(d: DMP) -> bool:
    """Whether the fit and rollout of DMPs with ``d``'s settings are linear (scaling ``"none"``, 2-D)."""
    return d.scaling == "none" and d.n_dims == 2


def recombination_map(d: DMP, t: NDArray[np.float64]) -> RecombinationMap:
    """The cached :class:`RecombinationMap` of DMPs with ``d``'s settings on the grid ``t`` (T,) [s]
    (starting at 0); requires :func:`linear_recombination`."""
    key = (dmp_settings(d), t.tobytes())
    hit = _CACHE.get(key)
    if hit is not None:
        _CACHE.move_to_end(key)
        return hit
    T = t.size
    tau = float(t[-1] - t[0])
    probe = DMP(2, n_basis=d.n_basis, alpha_z=d.alpha_z, beta_z=d.beta_z, gamma=d.gamma, scaling=d.scaling,
                ridge=d.ridge)
    L = np.zeros((d.n_basis, T))
    eye = np.eye(T)
    for j in range(0, T, 2):
        k = min(j + 1, T - 1)
        w = probe.fit(t, np.column_stack([eye[j], eye[k]])).weights
        L[:, j], L[:, k] = w[:, 0], w[:, 1]
    aff = probe.affine(t, x0=np.zeros(2), g=np.ones(2), tau=tau)
    m = RecombinationMap(t.copy(), aff.x_free[:, 0].copy(), aff.Gx.copy(), aff.Gx @ L)
    _CACHE[key] = m
    if len(_CACHE) > _MAXSIZE:
        _CACHE.popitem(last=False)
    return m
