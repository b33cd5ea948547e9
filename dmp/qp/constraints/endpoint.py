"""Boundary conditions at the end of the motion: fixed end point, zero end velocity."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint
from tooltransfer.validation import check_array


class _AtEnd(Constraint):
    """Equality rows at the last sample of the grid."""

    equality = True

    def samples(self, t: NDArray[np.float64]) -> NDArray[np.intp]:
        return np.array([t.size - 1])


class FixedEndPoint(_AtEnd):
    """``x(t_end) = point`` [m]. Without it a constrained rollout stops short of the goal, since the
    DMP only converges to ``g`` asymptotically."""

    def __init__(self, point: ArrayLike, *, family: str = "endpoint") -> None:
        super().__init__(family)
        self.point = check_array(point, "point", ndim=1)

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        n = self.point.size
        return Coefficients(k, np.eye(n)[None], None, self.point[None])


class ZeroEndVelocity(_AtEnd):
    """``v(t_end) = 0`` [m/s]."""

    def __init__(self, *, family: str = "end_velocity") -> None:
        super().__init__(family)

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        n = x_lin.shape[1]
        return Coefficients(k, None, np.eye(n)[None], np.zeros((1, n)))
