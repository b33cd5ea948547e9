"""Named switch cases (the paper's Fig. 11) and random switches (tests, benchmark).

Fig. 11 gives no coordinates; the object sits 160 mm in front of the Omni (inside its reach, as the
paper scenarios of :mod:`tooltransfer.planner.planning.ss.paper_cases`), contact points in the middle of the faces'
ranges:

* ``fig11a``: T-shape, the object contact moves from the object's right (the crossbar's ``left``
  end pushing leftward) to its bottom (the crossbar's ``top`` pushing forward);
* ``fig11a_stem``: the same with the stem's left side (``stem_left``) at the object's right, the
  object under the crossbar (the tool library's note on Fig. 11a);
* ``fig11b``: trapezoid, from the object's right (``left`` face pushing leftward) to its bottom-right
  (the ``inclined`` face pushing at 0.75 pi).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tooltransfer.planner.planning.ss.switch_task import SwitchTask
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.platform import OmniPlatform

#: The object's centre in the Fig. 11 cases [m].
FIG11_CENTRE = (0.0, 0.16)

FIG11: dict[str, tuple[str, str, str]] = {
    "fig11a": ("t_shape", "left", "top"),
    "fig11a_stem": ("t_shape", "stem_left", "top"),
    "fig11b": ("trapezoid", "left", "inclined"),
}


def fig11_task(name: str) -> SwitchTask:
    """The named Fig. 11 case (module docstring)."""
    tool, a, b = FIG11[name]
    return SwitchTask(load_tool(tool), a, b, np.array(FIG11_CENTRE))


LIBRARY_TOOLS: tuple[str, ...] = ("finger", "slope", "t_shape", "trapezoid", "i_shape", "l_shape")


def random_task(rng: np.random.Generator, tools: Sequence[str] = LIBRARY_TOOLS, *,
                obstacle_prob: float = 0.0) -> SwitchTask:
    """A random switch: a library tool, two different faces (random contact points), the disc
    object 130-190 mm from the Omni's axis within +-0.45 rad of straight ahead, and with probability
    ``obstacle_prob`` a disc obstacle (radius 8-15 mm) 45-70 mm from the object."""
    tool = load_tool(str(rng.choice(list(tools))))
    a, b = rng.choice(len(tool.faces), size=2, replace=False)
    fa, fb = tool.faces[int(a)], tool.faces[int(b)]
    r, th = rng.uniform(0.13, 0.19), np.pi / 2 + rng.uniform(-0.45, 0.45)
    centre = r * np.array([np.cos(th), np.sin(th)])
    obstacles: tuple[Disc, ...] = ()
    if rng.uniform() < obstacle_prob:
        d, phi = rng.uniform(0.045, 0.07), rng.uniform(0, 2 * np.pi)
        obstacles = (Disc(centre + d * np.array([np.cos(phi), np.sin(phi)]), rng.uniform(0.008, 0.015)),)
    return SwitchTask(
        tool, fa.name, fb.name, centre, s_from=float(rng.uniform(*fa.contact_range)),
        s_to=float(rng.uniform(*fb.contact_range)), obstacles=obstacles, platform=OmniPlatform(a_t=tool.a_t),
    )
