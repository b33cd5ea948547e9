"""The demonstration task (the paper's Figs. 2, 4 and 8), in the world frame [m].

The paper prints no coordinates (DESIGN section 9); this layout keeps the figures' qualitative
shape inside the default Omni's reach with tool 1: from a start in front of the arm to the right,
forward with the upper face, leftward with the left face round an obstacle, forward again, and
leftward into a target square up and to the left. Every corner is inside the reach sector of the
face that pushes there (checked in tests/test_operator.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from tools.objects import Disc


@dataclass(frozen=True)
class DemoScene:
    """Start, the corners the operator aims at (faces between them), obstacle and target square.

    Attributes:
        corners: (5, 2) [m]: start, three corners, target centre.
        faces: face pushing along each leg (tool 1).
        obstacle: a disc the puck must go round.
        target_half: half side of the target square [m].
    """

    corners: NDArray[np.float64] = field(
        default_factory=lambda: np.array([[0.045, 0.12], [0.045, 0.16], [-0.005, 0.16], [-0.005, 0.19],
                                          [-0.045, 0.19]])
    )
    faces: tuple[str, ...] = ("upper", "left", "upper", "left")
    obstacle: Disc = field(default_factory=lambda: Disc(np.array([0.015, 0.13]), 0.007))
    target_half: float = 0.01

    @property
    def start(self) -> NDArray[np.float64]:
        return self.corners[0]

    @property
    def target(self) -> NDArray[np.float64]:
        return self.corners[-1]

    def in_target(self, xy: NDArray[np.float64]) -> bool:
        """Whether the object centre ``xy`` (2,) is inside the target square."""
        return bool(np.all(np.abs(np.asarray(xy) - self.target) <= self.target_half))


DEMO_SCENE = DemoScene()
