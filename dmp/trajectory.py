"""Result of a DMP rollout."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class Rollout:
    """A sampled motion.

    Attributes:
        t: sample times, shape (T,) [s].
        x: positions, shape (T, n) [m].
        v: velocities, shape (T, n) [m/s].
        a: accelerations, shape (T, n) [m/s^2].
    """

    t: NDArray[np.float64]
    x: NDArray[np.float64]
    v: NDArray[np.float64]
    a: NDArray[np.float64]

    def path_length(self) -> float:
        """Length of the polyline through the sampled positions [m]."""
        return float(np.linalg.norm(np.diff(self.x, axis=0), axis=1).sum())
