"""Where the object sits relative to the Omni when a face of the tool pushes it.

On the Omni the tool heading follows the waist: ``yaw = base_yaw + q1 - pi/2`` (docs/design.md section 7),
and the tool centre point is ``p_t = b + R(a) (u, d_t)`` with ``a = base_yaw + q1``, ``u`` the
arm-plane reach and ``d_t`` the tool row's offset. A face touching the object puts the object's
centre at ``c`` in the tool frame (contact point plus the object radius along the face's normal),
so the object is at

    p_o = p_t + R(yaw) c = b + R(a) (u + c_y, d_t - c_x)

(``R(a - pi/2) c = R(a) (c_y, -c_x)``). For a face, the object positions the Omni can push from
form the same kind of annular sector as the tool centre point's: reach ``u + c_y`` and offset
``d_t - c_x``. Knowing ``p_o`` gives ``a`` in closed form, hence the heading and the face's push
direction in the world: :class:`FaceFrame`.

The directions a face may push the object in are those of its friction cone about the face's
outward normal (docs/design.md section 10: a round object under a flat face moves inside
``|phi_c| <= atan(mu)`` about the normal, whatever the tool does), narrowed to the options'
``friction_cone_fraction`` of it and intersected with the tool file's ``push_angle +- theta_b`` (the
operator's preference): :attr:`FaceFrame.push_angle` and :attr:`FaceFrame.theta_b` describe that
admissible cone (its middle and half-width), so every consumer of the frame plans inside it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.problems.task import OEOptions, schema_default
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.reach import reach_sector
from tooltransfer.tools.pose import wrap_angle
from tooltransfer.validation import check_array

if TYPE_CHECKING:
    from tooltransfer.planner.planning.setting import Setting

#: Default share of the friction cone's half-angle a plan may use (``oe.friction_cone_fraction``, the task schema's).
CONE_FRACTION: float = schema_default(OEOptions, "friction_cone_fraction")


@dataclass(frozen=True)
class FaceFrame:
    """A face of a tool pushing a disc object on the Omni.

    Attributes:
        face: face name.
        centre_in_tool: shape (2,), the object's centre in the tool frame while in contact [m].
        push_angle: middle of the admissible cone of object directions, tool frame [rad].
        theta_b: half-width of the admissible cone [rad] (see the module docstring).
        base: shape (2,), world position of the joint-1 axis [m].
        base_yaw: [rad].
        waist: ``(a_lo, a_hi)``, range of ``a = base_yaw + q1`` [rad].
        reach: ``(u_in, u_out)``, range of the object's arm-plane coordinate ``u + c_y`` [m].
        offset: the object's offset ``d_t - c_x`` from the arm's plane [m].
        normal_angle: the face's outward normal in the tool frame [rad].
        s: arc length [m] of the contact point along the face (from its start).
    """

    face: str
    centre_in_tool: NDArray[np.float64]
    push_angle: float
    theta_b: float
    base: NDArray[np.float64]
    base_yaw: float
    waist: tuple[float, float]
    reach: tuple[float, float]
    offset: float
    normal_angle: float = 0.0
    s: float = 0.0

    @classmethod
    def build(cls, setting: Setting, face: str, *, s: float | None = None,
              friction_cone_fraction: float = CONE_FRACTION) -> FaceFrame:
        """Frame of ``face`` of ``setting``'s tool on its Omni for its object (radius, friction cone
        ``atan(mu)``), contact at fraction ``s`` along the face (default the middle of its contact
        range); the planned directions may use ``friction_cone_fraction`` (0, 1] of the friction
        cone's half-angle (the OE options' field: a plan that survives an error in ``mu``).

        Raises:
            InputError: ``friction_cone_fraction`` outside (0, 1], ``s`` outside the contact range, a
                face that places the object in front of the arm's axis, or a face whose cone
                (``push_angle +- theta_b``) and friction cone do not overlap (it cannot push at all).
        """
        if not 0.0 < float(friction_cone_fraction) <= 1.0:
            raise InputError("oe.friction_cone_fraction", "a number in (0, 1]", repr(friction_cone_fraction))
        tool, platform = setting.tool, setting.platform
        half_angle = friction_cone_fraction * setting.mechanics.friction_angle
        f = tool.face(face)
        s0, s1 = f.contact_range
        s = 0.5 * (s0 + s1) if s is None else float(s)
        if not s0 - 1e-12 <= s <= s1 + 1e-12:
            raise InputError("s", f"a fraction in face {face!r}'s contact range [{s0}, {s1}]", repr(s))
        c = f.point(s) + setting.radius * f.normal
        sec = reach_sector(platform)
        u_lo, u_hi = sec.u_range[0] + c[1], sec.u_range[1] + c[1]
        if u_lo <= 0.0:
            raise InputError("tool", f"face {face!r} placing the object in front of the arm's axis", f"u {u_lo}")
        lo, hi = admissible_cone(f.normal_angle, f.push_angle, f.theta_b, half_angle)
        if hi <= lo:
            raise InputError(f"tool.faces.{face}", "a push cone (push_angle +- theta_b) that overlaps the friction "
                             f"cone (+-{np.degrees(half_angle):.1f} deg about the normal)",
                             f"no overlap (push_angle {f.push_angle:.4g}, normal {f.normal_angle:.4g} rad)")
        return cls(
            face=face,
            centre_in_tool=c,
            push_angle=0.5 * (lo + hi),
            theta_b=0.5 * (hi - lo),
            base=sec.centre.copy(),
            base_yaw=sec.base_yaw,
            waist=(sec.base_yaw + sec.q1_range[0], sec.base_yaw + sec.q1_range[1]),
            reach=(u_lo, u_hi),
            offset=D_TOOL - c[0],
            normal_angle=f.normal_angle,
            s=s * f.length,
        )

    def normal_direction(self, p: ArrayLike) -> NDArray[np.float64]:
        """World direction [rad] (K,) of the face's outward normal with the object at ``p`` (K, 2) [m]."""
        return self.heading(p) + self.normal_angle

    def waist_angle(self, p: ArrayLike) -> NDArray[np.float64]:
        """``a = base_yaw + q1`` [rad] (K,) with the object at ``p`` (K, 2) [m] (forward branch).

        Points closer to the axis than ``|offset|`` have no forward solution; they get the angle of
        the nearest reachable radius (the caller's reach rows keep the path away from there).
        """
        d = np.atleast_2d(np.asarray(p, dtype=np.float64)) - self.base
        r2 = np.einsum("ij,ij->i", d, d)
        u = np.sqrt(np.maximum(r2 - self.offset**2, 1e-18))
        return np.arctan2(d[:, 1], d[:, 0]) - np.arctan2(self.offset, u)

    def heading(self, p: ArrayLike) -> NDArray[np.float64]:
        """Tool yaw [rad] (K,) with the object at ``p`` (K, 2) [m]."""
        return self.waist_angle(p) - np.pi / 2

    def push_direction(self, p: ArrayLike) -> NDArray[np.float64]:
        """World push direction [rad] (K,) of the face with the object at ``p`` (K, 2) [m]."""
        return self.heading(p) + self.push_angle

    def tool_pose(self, p: ArrayLike) -> NDArray[np.float64]:
        """Tool poses (K, 3): ``x, y`` [m] of the tool centre point and yaw [rad], object at ``p``."""
        pts = np.atleast_2d(check_array(p, "p", shape=(None, 2)))
        yaw = self.heading(pts)
        c, s = np.cos(yaw), np.sin(yaw)
        cx, cy = self.centre_in_tool
        xy = pts - np.stack([c * cx - s * cy, s * cx + c * cy], axis=1)
        return np.column_stack([xy, yaw])


def admissible_cone(
    normal_angle: float, push_angle: float, theta_b: float, friction_half: float
) -> tuple[float, float]:
    """The tool-frame directions ``[lo, hi]`` [rad] a face may push in: its friction cone
    ``normal_angle +- friction_half`` intersected with the operator's ``push_angle +- theta_b``
    (``hi <= lo`` when they do not overlap)."""
    off = wrap_angle(push_angle - normal_angle)
    lo = max(-friction_half, off - theta_b)
    hi = min(friction_half, off + theta_b)
    return normal_angle + lo, normal_angle + hi
