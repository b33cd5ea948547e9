"""Where the object sits relative to the Omni when a face of the tool pushes it.

On the Omni the tool heading follows the waist: ``yaw = base_yaw + q1 - pi/2`` (DESIGN section 7),
and the tool centre point is ``p_t = b + R(a) (u, d_t)`` with ``a = base_yaw + q1``, ``u`` the
arm-plane reach and ``d_t`` the tool row's offset. A face touching the object puts the object's
centre at ``c`` in the tool frame (contact point plus the object radius along the face's normal),
so the object is at

    p_o = p_t + R(yaw) c = b + R(a) (u + c_y, d_t - c_x)

(``R(a - pi/2) c = R(a) (c_y, -c_x)``). For a face, the object positions the Omni can push from
form the same kind of annular sector as the tool centre point's: reach ``u + c_y`` and offset
``d_t - c_x``. Knowing ``p_o`` gives ``a`` in closed form, hence the heading and the face's push
direction in the world: :class:`FaceFrame`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from dmp.errors import InputError
from dmp.validation import check_array
from tools.model import Tool
from tools.objects import OBJECT_RADIUS
from tools.omni.dh import D_TOOL
from tools.omni.platform import OmniPlatform
from tools.omni.reach import reach_sector


@dataclass(frozen=True)
class FaceFrame:
    """A face of a tool pushing a disc object on the Omni.

    Attributes:
        face: face name.
        centre_in_tool: shape (2,), the object's centre in the tool frame while in contact [m].
        push_angle: the face's push direction in the tool frame [rad].
        theta_b: the face's cone half-angle [rad].
        base: shape (2,), world position of the joint-1 axis [m].
        base_yaw: [rad].
        waist: ``(a_lo, a_hi)``, range of ``a = base_yaw + q1`` [rad].
        reach: ``(u_in, u_out)``, range of the object's arm-plane coordinate ``u + c_y`` [m].
        offset: the object's offset ``d_t - c_x`` from the arm's plane [m].
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

    @classmethod
    def build(
        cls, tool: Tool, face: str, platform: OmniPlatform, *, s: float | None = None, radius: float = OBJECT_RADIUS
    ) -> FaceFrame:
        """Frame of ``face`` of ``tool`` on ``platform``, contact at fraction ``s`` along the face
        (default the middle of its contact range), object a disc of ``radius`` [m]."""
        f = tool.face(face)
        s0, s1 = f.contact_range
        s = 0.5 * (s0 + s1) if s is None else float(s)
        if not s0 - 1e-12 <= s <= s1 + 1e-12:
            raise InputError("s", f"a fraction in face {face!r}'s contact range [{s0}, {s1}]", repr(s))
        c = f.point(s) + radius * f.normal
        sec = reach_sector(platform)
        u_lo, u_hi = sec.u_range[0] + c[1], sec.u_range[1] + c[1]
        if u_lo <= 0.0:
            raise InputError("tool", f"face {face!r} placing the object in front of the arm's axis", f"u {u_lo}")
        return cls(
            face=face,
            centre_in_tool=c,
            push_angle=f.push_angle,
            theta_b=f.theta_b,
            base=sec.centre.copy(),
            base_yaw=sec.base_yaw,
            waist=(sec.base_yaw + sec.q1_range[0], sec.base_yaw + sec.q1_range[1]),
            reach=(u_lo, u_hi),
            offset=D_TOOL - c[0],
        )

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
