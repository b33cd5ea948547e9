"""The OE figures are written (Fig. 10 and Fig. 14 styles) from real plans."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image as mpimg
import numpy as np

from tooltransfer.planner.apps.plots.push_plans import plot_push_plans
from tooltransfer.planner.apps.plots.safety_margin import plot_safety_margin
from tooltransfer.planner.planning.oe import QPOptions, condense_qp
from tooltransfer.planner.planning.oe.mapping_variant import condense_mapping
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.problems.fit_cases import minimum_jerk
from tooltransfer.tools import Disc, load_tool
from tooltransfer.tools.objects import DiscObject
from tooltransfer.tools.omni.platform import OmniPlatform


def test_push_plan_and_safety_margin_figures(tmp_path: Path) -> None:
    tool = load_tool("slope")
    plat = OmniPlatform(a_t=tool.a_t)
    n = 160
    t = np.linspace(0, 6, n)
    x = np.vstack([minimum_jerk(np.array([0.05, 0.12]), np.array([-0.014, 0.146]), n // 2),
                   minimum_jerk(np.array([-0.014, 0.146]), np.array([-0.068, 0.173]), n - n // 2)])
    obs = Disc(np.array([0.01, 0.095]), 0.006)
    setting = Setting(tool, plat, DiscObject(0.0175), obstacles=(obs,))
    plans = {"mapping": condense_mapping(t, x, setting),
             "qp": condense_qp(t, x, setting, options=QPOptions(candidates=3))}
    assert plans["qp"].status == "solved", plans["qp"].reason
    assert plans["qp"].metrics["obstacle_clearance_min"] >= 0.005 - 1e-6
    for path in (plot_push_plans(plans, tool, tmp_path / "fig10.png", radius=0.0175, obstacles=[obs], margin=0.005,
                                 target=x[-1]),
                 plot_safety_margin(x, obs, plans, tmp_path / "fig14.png", radius=0.0175)):
        img = mpimg.imread(path)
        assert img.shape[0] > 300 and img.shape[1] > 600
        assert img[..., :3].std() > 0.05  # something was drawn
