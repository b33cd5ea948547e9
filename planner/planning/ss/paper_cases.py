"""The paper's cases built from the committed demonstrations (docs/design.md section 5, Figs. 8 and 10).

:func:`default_oe_skill` learns the universal OE skill from ``problems/data/finger_demos`` (tool 1):
segmentation, recovery with the face-change corners as fixed points, one DMP. :func:`transfer_case`
generalizes it to the demonstration task's start and target for tool 2 (``slope``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.learning.oe_skill import OESkill, learn_oe_skill
from tooltransfer.planner.learning.segmentation import segment
from tooltransfer.planner.planning.oe.generalize import generalize
from tooltransfer.problems import FINGER_DEMOS
from tooltransfer.problems.dataset import load_dataset
from tooltransfer.problems.demo_scene import DEMO_SCENE
from tooltransfer.problems.task import MAPPING_K
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.platform import OmniPlatform

DEFAULT_DATASET = FINGER_DEMOS


@cache
def default_oe_skill(k: float = MAPPING_K, n_basis: int = 30) -> OESkill:
    """The universal OE skill learned from the default dataset."""
    ds = load_dataset(DEFAULT_DATASET)
    tool = load_tool(ds.meta.tool)
    demos, fixed = [], []
    for d in ds.demonstrations:
        pushes = segment(d, tool).demo_pushes(d)
        demos.append(pushes)
        fixed.append([i for i in range(len(pushes) - 1) if pushes[i].face != pushes[i + 1].face])
    return learn_oe_skill(demos, tool, k=k, n_basis=n_basis, fixed=fixed)


@dataclass(frozen=True)
class TransferCase:
    """The transfer to tool 2 on the demonstration task: generalized universal path ``t`` (T,) [s],
    ``x`` (T, 2) [m], the tool, the Omni carrying it, the target [m] and the obstacle."""

    t: NDArray[np.float64]
    x: NDArray[np.float64]
    tool: Tool
    platform: OmniPlatform
    target: NDArray[np.float64]
    obstacles: tuple[Disc, ...]


def transfer_case(tool: str = "slope") -> TransferCase:
    """The paper's transfer case (Fig. 10): the default skill generalized for ``tool``."""
    skill = default_oe_skill()
    t, x, _ = generalize(skill.dmp, DEMO_SCENE.start, DEMO_SCENE.target)
    tl = load_tool(tool)
    return TransferCase(t, x, tl, OmniPlatform(a_t=tl.a_t), DEMO_SCENE.target.copy(), (DEMO_SCENE.obstacle,))
