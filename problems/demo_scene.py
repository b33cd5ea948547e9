"""Named scenes of the paper's tasks, in the world frame of docs/design.md section 2 (SI units: metres).

The paper prints no start, target or obstacle coordinates (docs/design.md section 9). :data:`DEMO_SCENE`
is this project's choice for the demonstration task of Figs. 2, 4 and 8, keeping the figures'
qualitative layout inside the default Omni's reach with tool 1 (``finger``): the puck starts in
front of the arm to the right, is pushed forward with the upper face, leftward with the left face,
forward again and leftward into a target square up and to the left. The disc obstacle sits inside
the first corner, on the straight (and the diagonal) way from the start to the target, so a tool
that can push diagonally must go round it. Where it can be is narrow: tool 1's body reaches 30 mm
behind its head towards the Omni, so the obstacle must stay clear of the body while the left face
pushes along the second leg and while the tool goes round the puck at the second and third corners
(a layout with the obstacle at (15, 130) mm, radius 7 mm, and the second corner at x = -5 mm made
the arm catch on it), and 7 mm clear of the start (the planner's safety margin is 5 mm).

Every corner is inside the Omni's reach sector, and every tool path the scripted operator executes
is checked by the inverse kinematics (the simulator refuses unreachable points); see
``tests/test_operator.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from tooltransfer.tools.objects import Disc


@dataclass(frozen=True)
class DemoScene:
    """Start, the corners the operator aims at (faces between them), obstacles and target square.

    Attributes:
        corners: (C, 2) [m]: start, the corners, target centre (C = len(faces) + 1).
        faces: face of tool 1 pushing along each leg.
        obstacles: discs the puck (and the tool) must stay clear of.
        target_half: half side of the target square [m].
    """

    corners: NDArray[np.float64] = field(
        default_factory=lambda: np.array([[0.045, 0.12], [0.045, 0.16], [-0.022, 0.16], [-0.022, 0.19],
                                          [-0.052, 0.19]])
    )
    faces: tuple[str, ...] = ("upper", "left", "upper", "left")
    obstacles: tuple[Disc, ...] = field(default_factory=lambda: (Disc(np.array([0.015, 0.125]), 0.005),))
    target_half: float = 0.01

    @property
    def start(self) -> NDArray[np.float64]:
        """Start of the object's centre (2,) [m]."""
        return self.corners[0]

    @property
    def target(self) -> NDArray[np.float64]:
        """Centre of the target square (2,) [m]."""
        return self.corners[-1]

    @property
    def obstacle(self) -> Disc:
        """The (first) obstacle."""
        return self.obstacles[0]

    def in_target(self, xy: NDArray[np.float64]) -> bool:
        """Whether the object centre ``xy`` (2,) [m] is inside the target square."""
        return bool(np.all(np.abs(np.asarray(xy) - self.target) <= self.target_half))

    def to_dict(self) -> dict:
        """Plain values for ``meta.yaml`` (the dataset's ``scene`` block) [m]."""
        return {"start": self.start.tolist(), "corners": self.corners.tolist(), "faces": list(self.faces),
                "obstacles": [{"centre": o.centre.tolist(), "radius": o.radius} for o in self.obstacles],
                "target": self.target.tolist(), "target_half": self.target_half}


DEMO_SCENE = DemoScene()
"""The demonstration task (Figs. 2, 4, 8) used by the scripted operator and the default dataset."""
