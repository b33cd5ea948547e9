r"""Coupling terms for stepwise DMP execution (:meth:`~tooltransfer.dmp.primitive.DMP.step`).

Obstacle coupling after Hoffmann et al. (ICRA 2009), "Biologically-inspired dynamical systems for
movement generation: automatic real-time goal adaptation and obstacle avoidance": the velocity is
steered away from a point obstacle ``o`` by a term perpendicular to it,

$$
C = k\,R\,(\tau \dot x)\,\varphi\,e^{-\beta \varphi},
$$

where ``phi`` is the angle [rad] between the velocity and the direction ``o - x`` to the obstacle,
``R`` the rotation by +90 degrees about ``(o - x) x dx/dt`` (it turns the velocity away from the
obstacle), ``k`` a gain [1/rad] and ``beta`` [1/rad] how fast the term fades as the obstacle leaves
the heading. ``C`` is in the forcing term's units [m]; it vanishes at rest and for an obstacle
straight behind. An obstacle straight ahead (``phi = 0``) gives no term either: the rule steers
only what is already turning, as in the paper.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.validation import check_array, check_positive


def obstacle_coupling(
    x: ArrayLike,
    v: ArrayLike,
    obstacle: ArrayLike,
    tau: float,
    *,
    gain: float = 1000.0,
    beta: float = 20.0 / np.pi,
) -> NDArray[np.float64]:
    """The coupling term ``C`` (n,) [m] that steers a motion at ``x`` with velocity ``v`` from ``obstacle``.

    Args:
        x: position, shape (2,) or (3,) [m].
        v: velocity ``dx/dt``, the same shape [m/s].
        obstacle: the obstacle's point, the same shape [m].
        tau: the run's duration [s] (the DMP's velocity state is ``tau * v``).
        gain: ``k`` [1/rad], > 0.
        beta: ``beta`` [1/rad], > 0.
    """
    xa = check_array(x, "x", ndim=1)
    if xa.size not in (2, 3):
        raise InputError("x", "a planar (2,) or spatial (3,) position", f"shape {xa.shape}")
    va = check_array(v, "v", shape=xa.shape)
    oa = check_array(obstacle, "obstacle", shape=xa.shape)
    k, b, taua = check_positive(gain, "gain"), check_positive(beta, "beta"), check_positive(tau, "tau")
    to_obstacle = oa - xa
    speed, dist = float(np.linalg.norm(va)), float(np.linalg.norm(to_obstacle))
    if speed == 0.0 or dist == 0.0:
        return np.zeros(xa.size)
    cos_phi = float(np.clip(to_obstacle @ va / (speed * dist), -1.0, 1.0))
    phi = float(np.arccos(cos_phi))
    # R v for the rotation by +90 degrees about r = (o - x) x v: r_hat x v (v is perpendicular to r)
    r = np.cross(np.append(to_obstacle, 0.0) if xa.size == 2 else to_obstacle,
                 np.append(va, 0.0) if xa.size == 2 else va)
    r_norm = float(np.linalg.norm(r))
    if r_norm == 0.0:  # moving straight at or away from the obstacle: no side to turn to
        return np.zeros(xa.size)
    turned = np.cross(r / r_norm, np.append(va, 0.0) if xa.size == 2 else va)[: xa.size]
    return np.asarray(k * taua * turned * phi * np.exp(-b * phi), dtype=np.float64)
