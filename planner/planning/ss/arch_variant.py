"""A geometric switch path: the tool backs off one face's contact, goes round the object on an arch
that bulges out until the swept tool keeps a clearance from it (checked with shapely on the tool
outline at the heading the Omni imposes), and approaches the other face's contact.

It needs no learned skill: the scripted operator uses it, and the planner offers it as the ``arch``
switch variant, the geometric reference of the skill-based ones (DMP recombination, CasADi paths),
and as the fallback of a variant whose local solve finds no path (:mod:`tooltransfer.planner.planning.switches`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.errors import ToolTransferError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import OBJECT_RADIUS, Disc
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import placed_outlines, wrap_angle


class NoArch(ToolTransferError):
    """No arch within reach keeps the clearance."""


def swept_clearance(tool: Tool, platform: OmniPlatform, xy: NDArray[np.float64], obj: NDArray[np.float64],
                    radius: float = OBJECT_RADIUS) -> float:
    """Least distance [m] between the tool outline along the path ``xy`` (K, 2) (heading from the
    Omni) and the disc object at ``obj`` (2,); the samples should be dense (<= 1 mm apart)."""
    yaw = joint_path(platform, xy).heading
    puck = shapely.Point(obj).buffer(radius, quad_segs=32)
    return float(shapely.distance(placed_outlines(tool.outline.exterior.coords, xy, yaw), puck))


def arch_path(
    tool: Tool, platform: OmniPlatform, a: NDArray[np.float64], b: NDArray[np.float64], obj: NDArray[np.float64],
    clearance: float, *, n: int = 60, max_bulge: float = 0.06, obstacles: Sequence[Disc] = (),
    radius: float = OBJECT_RADIUS,
) -> NDArray[np.float64]:
    """Tool centre point path (n, 2) [m] from ``a`` to ``b`` round the object at ``obj``: polar
    interpolation about the object, the short way round first, hugging the object by up to 9 mm or
    bulging out by up to ``max_bulge``
    until every point is reachable and the tool keeps ``clearance`` [m] (or 90% of the clearance
    at the ends, when an end is closer) from the object and from the disc ``obstacles`` (the tool's
    body reaches behind its head, so clearing the object is not enough). Raises :class:`NoArch`."""
    if np.any(joint_path(platform, np.vstack([a, b])).violation > 0.0):  # no heading there: no arch either
        raise NoArch(f"an end of the switch ({np.round(a, 4).tolist()}, {np.round(b, 4).tolist()}) out of reach")
    ends = swept_clearance(tool, platform, np.vstack([a, b]), obj, radius)
    clearance = min(clearance, 0.9 * ends)  # an end closer than that cannot be left or reached otherwise
    da, db = a - obj, b - obj
    ta, tb = np.arctan2(da[1], da[0]), np.arctan2(db[1], db[0])
    dth = wrap_angle(tb - ta)
    s = np.linspace(0.0, 1.0, n)
    out = np.arange(0.004, max_bulge + 1e-12, 0.004)
    # hugging the object first (an obstacle is usually farther out), then bulging out
    for bulge in np.concatenate([[0.0, -0.003, -0.006, -0.009], out]):
        for way in (dth, dth - np.copysign(2 * np.pi, dth)):
            r = (1 - s) * np.hypot(*da) + s * np.hypot(*db) + bulge * np.sin(np.pi * s)
            th = ta + s * way
            path = obj + r[:, None] * np.column_stack([np.cos(th), np.sin(th)])
            if (
                np.all(joint_path(platform, path).violation == 0.0)
                and swept_clearance(tool, platform, path, obj, radius) >= clearance
                and all(swept_clearance(tool, platform, path, o.centre, o.radius) >= clearance for o in obstacles)
            ):
                return path
    raise NoArch(f"no way round the object at {np.round(obj, 4).tolist()} within reach")


def switch_path(
    tool: Tool, platform: OmniPlatform, obj: NDArray[np.float64], pose_a: NDArray[np.float64], dir_a: float,
    pose_b: NDArray[np.float64], dir_b: float, *, back_off: float = 0.012, clearance: float = 0.004,
    obstacles: Sequence[Disc] = (), radius: float = OBJECT_RADIUS,
) -> NDArray[np.float64]:
    """Whole switch (K, 2): back off ``back_off`` [m] from contact pose ``pose_a`` against its push
    direction ``dir_a`` [rad], arch round the object, approach ``pose_b`` along ``dir_b``."""
    ua, ub = np.array([np.cos(dir_a), np.sin(dir_a)]), np.array([np.cos(dir_b), np.sin(dir_b)])
    a0, b0 = np.asarray(pose_a[:2], float), np.asarray(pose_b[:2], float)
    a1, b1 = a0 - back_off * ua, b0 - back_off * ub
    arch = arch_path(tool, platform, a1, b1, obj, clearance, obstacles=obstacles, radius=radius)
    lin = np.linspace(0.0, 1.0, 8)[:, None]
    return np.vstack([a0 + lin * (a1 - a0), arch[1:-1], b1 + lin * (b0 - b1)])
