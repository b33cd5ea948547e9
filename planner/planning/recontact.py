"""Re-contacts: the same face leaves the resting object and touches it again elsewhere along the face.

When one contact cannot carry a push (the contact rolls along the face as the object moves sideways
and the heading turns, docs/design.md section 10), the push is split (:mod:`tooltransfer.planner.planning.oe.contacts`)
and the tool moves, while the object rests, from the contact pose where one piece ends to the one where the
next begins: it backs off along the face's normal by ``back_off``, shifts (the heading following
the Omni's waist on the way) and approaches along the new normal. The move is checked like a
switch: within the Omni's reach at every millimetre, the tool clear of the object between the two
contacts and :data:`~tooltransfer.planner.planning.tool_clearance.TOOL_MARGIN` from the obstacles
throughout (shapely, on the outline at the heading the Omni imposes; the margin of a solved plan and of
the closed loop's safety envelope). The back-off doubles, up to ``4 * back_off``, until the shift clears the object.
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.planner.planning.assemble import SwitchPlanner
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.ss.result import SwitchPath
from tooltransfer.planner.planning.switches import densify
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.pose import placed_outlines, rotation


def swept_distance(tool: Tool, xy: NDArray[np.float64], yaw: NDArray[np.float64], shape: shapely.Geometry) -> float:
    """Least distance [m] between the tool outline at poses ``xy`` (K, 2), ``yaw`` (K,) and ``shape``."""
    if len(xy) == 0:
        return float("inf")
    return float(shapely.distance(placed_outlines(tool.outline.exterior.coords, xy, yaw), shape))


def recontact_planner(setting: Setting, back_off: float = 0.002) -> SwitchPlanner:
    """The re-contact move in ``setting`` as a :data:`tooltransfer.planner.planning.assemble.SwitchPlanner`
    (``face_a == face_b``; ``back_off`` [m]: the first distance backed off along the face's normal)."""
    tool, platform, radius = setting.tool, setting.platform, setting.radius
    shapes = [o.polygon() if isinstance(o, Disc) else o for o in setting.obstacles]

    def plan(obj: NDArray[np.float64], face_a: str, pose_a: NDArray[np.float64], face_b: str,
             pose_b: NDArray[np.float64]) -> SwitchPath:
        normal = tool.face(face_a).normal
        puck = shapely.Point(obj).buffer(radius, quad_segs=32)
        reason = "no re-contact path"
        for d in back_off * np.array([1.0, 2.0, 4.0]):
            na, nb = rotation(float(pose_a[2])) @ normal, rotation(float(pose_b[2])) @ normal
            corners = np.vstack([pose_a[:2], pose_a[:2] - d * na, pose_b[:2] - d * nb, pose_b[:2]])
            dense = densify(corners, 0.0005)
            jp = joint_path(platform, dense)
            bad = np.flatnonzero(jp.refused)
            if bad.size:
                return SwitchPath("recontact", "infeasible", f"the re-contact of {face_a!r} leaves the Omni's "
                                  f"reach at {np.round(dense[bad[0]], 4).tolist()} m")
            inner = slice(2, -2) if len(dense) > 5 else slice(0, 0)
            gap = swept_distance(tool, dense[inner], jp.heading[inner], puck)
            if gap <= 0.0:
                reason = f"the re-contact of {face_a!r} sweeps into the object (back-off {1e3 * d:.0f} mm)"
                continue
            near = min((swept_distance(tool, dense, jp.heading, s) for s in shapes), default=np.inf)
            if near < TOOL_MARGIN:
                return SwitchPath("recontact", "infeasible", f"the re-contact of {face_a!r} at "
                                  f"{np.round(obj, 4).tolist()} m sweeps the tool into an obstacle"
                                  + (f" ({1e3 * near:.2f} mm from it; a solved plan keeps {1e3 * TOOL_MARGIN:g} mm)"
                                     if near > 0.0 else ""))
            return SwitchPath("recontact", "solved", xy=corners, object_clearance=gap, obstacle_clearance=float(near),
                              object_penetration=0.0, obstacle_penetration=0.0, info={"back_off": float(d)})
        return SwitchPath("recontact", "infeasible", reason)

    return plan
