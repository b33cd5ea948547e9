"""The rules a verdict is relative to: what any plan of the planner must satisfy (docs/design.md 11).

A plan moves the puck only while a face of the tool pushes it. While face ``f`` pushes, with the
contact at fraction ``s`` of the face's contact range:

- the puck's centre ``p`` is where the Omni can hold that contact: ``p = b + R(a) (u + c_y, d_t - c_x)``
  with the waist ``a`` in its range, the arm-plane reach ``u`` in the interval the shoulder and
  elbow limits allow at table height, and ``c = point(s) + R n`` the puck centre in the tool frame
  (:mod:`tooltransfer.planner.planning.oe.face_frame`);
- the puck's velocity points inside the face's admissible cone turned by the tool's heading there:
  the friction cone ``|phi| <= atan(mu)`` about the face's outward normal intersected with the tool
  file's ``push_angle +- theta_b`` (the plan's own narrowing ``oe.friction_cone_fraction`` is NOT
  assumed, so a verdict also holds for plans that use the whole friction cone);
- the puck's centre keeps ``radius + margin`` from every obstacle (the margin the plan can keep:
  :func:`tooltransfer.planner.solve.effective_margin`, with the hard check's 1e-5 m tolerance);
- the plan ends with the puck's centre within ``goal_tol`` of the target (the hard check's
  ``goal_error`` bound).

Everything else the planner demands (the contact staying on the face as it rolls, the tool body
clear of obstacles, switches and re-contacts that do not penetrate, the joints along the tool
path) is NOT assumed: leaving rules out only lets more plans through, so a certificate relative to
these rules holds for the planner's stricter ones. (The ``switch_separated`` certificate adds one of
them, with the tool's placements: a switch is a planar tool path within the joints that does not
penetrate an obstacle or the puck, :mod:`.switch_space`.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
import shapely.affinity

from tooltransfer.planner.planning.oe.face_frame import admissible_cone
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.omni.reach import reach_sector
from tooltransfer.tools.pushing.mechanics import PushMechanics

#: The hard check's tolerance [m] on the safety margin (``obstacle_clearance_min >= margin - 1e-5``).
MARGIN_TOL = 1e-5
#: The hard check's bound [m] on the final distance of the puck from the target.
GOAL_TOL = 1e-4


@dataclass(frozen=True)
class FaceRule:
    """What one face allows (module docstring), in the tool frame.

    Attributes:
        name: the face's name.
        cone: ``(lo, hi)`` [rad], the admissible directions of the puck's velocity in the tool frame
            (friction cone intersected with the tool file's cone); empty when ``hi < lo``.
        offset: ``(o_lo, o_hi)`` [m], range of the puck centre's offset ``d_t - c_x`` from the arm's
            plane over the contact range.
        reach: ``(v_lo, v_hi)`` [m], range of the puck centre's arm-plane coordinate ``u + c_y`` over
            the arm's reach interval and the contact range.
        core: convex polygons [m] in the tool frame with the puck's centre at the origin that the
            tool covers wherever the contact is on the face (for each convex piece of the outline, the
            intersection of its two placements with the contact at either end of the range): the
            tool body is there during every push with this face.
    """

    name: str
    cone: tuple[float, float]
    offset: tuple[float, float]
    reach: tuple[float, float]
    core: tuple[shapely.Polygon, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """JSON data."""
        return {"name": self.name, "cone": list(self.cone), "offset": list(self.offset), "reach": list(self.reach),
                "core": [np.asarray(p.exterior.coords)[:-1].tolist() for p in self.core]}


@dataclass(frozen=True)
class PushRules:
    """The rules of the module docstring for one task: tool faces on the Omni, obstacles, the goal.

    Attributes:
        faces: one :class:`FaceRule` per face that can push at all.
        base: shape (2,), the Omni's joint-1 axis in the world [m].
        waist: ``(a_lo, a_hi)`` [rad], range of ``base_yaw + q1``.
        radius: the puck's radius [m].
        margin: the safety margin [m] the plan keeps from obstacles (before ``MARGIN_TOL``).
        obstacles: the obstacles as shapely polygons [m] (discs kept exact in ``discs``).
        discs: ``(x, y, radius)`` of the disc obstacles [m].
        friction_half_angle: ``atan(mu)`` [rad].
        goal_tol: the final distance allowed from the target [m].
    """

    faces: tuple[FaceRule, ...]
    base: tuple[float, float]
    waist: tuple[float, float]
    radius: float
    margin: float
    polygons: tuple[shapely.Polygon, ...]
    discs: tuple[tuple[float, float, float], ...]
    friction_half_angle: float
    goal_tol: float = GOAL_TOL

    def to_dict(self) -> dict[str, Any]:
        """JSON data (the parameters a certificate is relative to)."""
        return {
            "faces": [f.to_dict() for f in self.faces], "base": list(self.base), "waist": list(self.waist),
            "radius": self.radius, "margin": self.margin, "margin_tol": MARGIN_TOL,
            "friction_half_angle": self.friction_half_angle, "goal_tol": self.goal_tol,
            "obstacles": [{"kind": "disc", "centre": [x, y], "radius": r} for x, y, r in self.discs]
            + [{"kind": "polygon", "vertices": np.asarray(p.exterior.coords)[:-1].tolist()} for p in self.polygons],
        }

    def clearance(self) -> float:
        """The distance [m] the puck's centre keeps from every obstacle (radius plus margin, less the
        hard check's tolerance)."""
        return self.radius + max(self.margin - MARGIN_TOL, 0.0)


def push_rules(tool: Tool, platform: OmniPlatform, obstacles: list, radius: float, mechanics: PushMechanics,
               margin: float, goal_tol: float = GOAL_TOL) -> PushRules:
    """The :class:`PushRules` of a tool on a platform among ``obstacles`` (discs and polygons) for a
    puck of ``radius`` [m] with push ``mechanics`` and the safety ``margin`` [m] the plan keeps."""
    sec = reach_sector(platform)
    friction = float(np.arctan(mechanics.mu))
    faces = []
    for f in tool.faces:
        lo, hi = admissible_cone(f.normal_angle, f.push_angle, f.theta_b, friction)
        if hi < lo:
            continue
        ends = [f.point(s) + radius * f.normal for s in f.contact_range]
        cx = sorted(float(c[0]) for c in ends)
        cy = sorted(float(c[1]) for c in ends)
        core = []
        for piece in tool.convex_pieces:
            both = shapely.intersection(shapely.affinity.translate(piece, -ends[0][0], -ends[0][1]),
                                        shapely.affinity.translate(piece, -ends[1][0], -ends[1][1]))
            if shapely.get_type_id(both) == 3 and both.area > 0.0:
                core.append(shapely.Polygon(np.asarray(both.exterior.coords)))
        faces.append(FaceRule(f.name, (float(lo), float(hi)), (D_TOOL - cx[1], D_TOOL - cx[0]),
                              (sec.u_range[0] + cy[0], sec.u_range[1] + cy[1]), tuple(core)))
    discs = tuple((float(o.centre[0]), float(o.centre[1]), float(o.radius)) for o in obstacles if isinstance(o, Disc))
    polygons = tuple(o for o in obstacles if not isinstance(o, Disc))
    return PushRules(tuple(faces), (float(sec.centre[0]), float(sec.centre[1])),
                     (sec.base_yaw + sec.q1_range[0], sec.base_yaw + sec.q1_range[1]), float(radius), float(margin),
                     polygons, discs, friction, goal_tol)


def setting_rules(setting: Setting) -> PushRules:
    """The :class:`PushRules` of a planning world (its tool, platform, obstacles, object, mechanics and
    margin)."""
    return push_rules(setting.tool, setting.platform, list(setting.obstacles), setting.radius, setting.mechanics,
                      setting.margin)
