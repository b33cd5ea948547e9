"""An objective term of the ``qp`` condensing fit that prices the contact's rolling along the faces.

While a face pushes, the sticking contact rolls along it at ``ds/dt = a(x) . v``
(:class:`tooltransfer.planner.planning.oe.constraints.ContactOnFace`); the contact must stay on the face, so a push
whose contact travels ``S`` along a face of usable length ``w`` needs about ``S / w`` contacts
(:mod:`tooltransfer.planner.planning.oe.contacts`). A fit free to wiggle sideways rolls the contact for nothing, and
each re-contact is a move of the tool. :class:`RollingPenalty` adds, per push window ``p``,

    lambda_p / T * 0.5 * sum_k (a_k . v_k)^2,      lambda_p = 2 price T T_p / w_p^2,

on the constraint grid (``T`` samples in all, ``T_p`` the window's duration [s]), with ``a_k`` taken
on the reference path: a push that rolls one usable length at an even rate over its window then
costs ``price``, the price of a re-contact, in the objective's units (half the mean squared
deviation [m^2]); rolling twice as far costs four times as much.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.affine import AffineRollout
from tooltransfer.dmp.qp.objectives import Objective, Quadratic
from tooltransfer.planner.planning.oe.constraints import heading_gradient
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.tools.pushing.inverse import FaceGeometry

if TYPE_CHECKING:
    from tooltransfer.planner.planning.setting import Setting

Window = tuple[FaceGeometry, FaceFrame, float, float, tuple[float, float]]
"""(face geometry, face frame, t_start [s], t_end [s], usable range (lo, hi) [m])."""


class RollingPenalty(Objective):
    """The priced rolling of the contacts over the push windows (module docstring).

    Args:
        windows: one entry per push (see :data:`Window`).
        reference: the reference path (T, 2) [m] on the constraint grid (where ``a`` is evaluated).
        setting: the world (the object's radius, the mechanics).
        price: a re-contact's price [m^2].
    """

    def __init__(self, windows: Sequence[Window], reference: NDArray[np.float64], setting: Setting,
                 price: float) -> None:
        self.windows, self.reference, self.setting, self.price = list(windows), reference, setting, float(price)

    def quadratic(self, aff: AffineRollout) -> Quadratic:
        t, n_all = aff.t, aff.t.size
        rows, consts, weights = [], [], []
        for face, frame, lo, hi, (s_lo, s_hi) in self.windows:
            k = np.flatnonzero((t >= lo - 1e-12) & (t <= hi + 1e-12))
            width = s_hi - s_lo
            if k.size < 2 or width <= 0:
                continue
            x = self.reference[k]
            psi = frame.heading(x)
            e = face.direction
            e_w = np.stack([np.cos(psi) * e[0] - np.sin(psi) * e[1], np.sin(psi) * e[0] + np.cos(psi) * e[1]], axis=1)
            a = -self.setting.mechanics.rolling * e_w - face.sigma * self.setting.radius * heading_gradient(frame, x)
            r, c0 = aff.rows(k, None, a)  # a . v = r @ w + c0
            lam = 2.0 * self.price * float(t[-1] - t[0]) * float(t[k[-1]] - t[k[0]]) / width**2
            rows.append(r)
            consts.append(c0)
            weights.append(np.full(k.size, lam / n_all))
        n = aff.n_weights
        if not rows:
            return Quadratic(np.zeros((n, n)), np.zeros(n))
        r, c0, wt = np.vstack(rows), np.concatenate(consts), np.concatenate(weights)
        return Quadratic((r * wt[:, None]).T @ r, r.T @ (wt * c0))
