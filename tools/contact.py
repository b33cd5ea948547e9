"""Tool poses that put a face in contact with the object so that a push moves it a given way.

Model (quasi-static, planar): face ``e`` touches the object with its outward normal ``n`` (world)
pointing into the object; the object moves along a direction inside the face's push cone. For a
disc of radius ``R`` centred at ``c`` the contact point on the object is ``q = c - R n``; for a
convex polygonal object it is the object's vertex farthest along ``-n``. The tool point ``p``
(tool frame, on the face) coincides with ``q``, so the tool origin is ``x = q - R(yaw) p``.

With ``yaw`` free, the tool is turned so that the face's central push direction equals the
desired motion direction: ``yaw = direction - push_angle``. On the Omni the heading is not free
(it follows ``q1``, which depends on where the tool is): :func:`contact_on_platform` solves that
coupling and reports whether the motion direction still lies in the cone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import DiscObject, ObjectModel
from tooltransfer.tools.omni.ik import IKResult, inverse_kinematics
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import Pose2D, wrap_angle
from tooltransfer.validation import check_array


@dataclass(frozen=True)
class Contact:
    """A tool pose with face ``face`` touching the object.

    Attributes:
        pose: tool pose in the world.
        face: face name.
        s: fraction along the face of the contact point.
        tool_point: shape (2,), contact point in the tool frame [m].
        object_point: shape (2,), contact point in the world [m] (on the object's boundary).
        normal: shape (2,), the face's outward unit normal in the world (into the object).
        direction: world direction [rad] the object is pushed in.
        cone_offset: signed angle [rad] from the face's central push direction to ``direction``.
    """

    pose: Pose2D
    face: str
    s: float
    tool_point: NDArray[np.float64]
    object_point: NDArray[np.float64]
    normal: NDArray[np.float64]
    direction: float
    cone_offset: float


def contact_pose(
    tool: Tool,
    face: str,
    centre: ArrayLike,
    direction: float,
    *,
    s: float | None = None,
    yaw: float | None = None,
    obj: ObjectModel | None = None,
) -> Contact:
    """Tool pose with ``face`` touching the object at ``centre`` to push it along ``direction``.

    Args:
        tool: the tool.
        face: name of the pushing face.
        centre: shape (2,), the object's centre (reference point) in the world [m].
        direction: desired object motion direction in the world [rad].
        s: fraction along the face of the contact point, inside the face's contact range;
            default the middle of the range.
        yaw: tool heading [rad]; default ``direction - push_angle``. When given, ``direction``
            must lie in the face's cone at that heading.
        obj: the object model; default the paper's 17.5 mm disc.

    Raises:
        InputError: ``s`` outside the contact range, or ``direction`` outside the cone.
    """
    f = tool.face(face)
    c = check_array(centre, "centre", shape=(2,))
    direction = float(check_array(direction, "direction", ndim=0))
    model = obj if obj is not None else DiscObject()
    s0, s1 = f.contact_range
    if s is None:
        s = 0.5 * (s0 + s1)
    if not s0 - 1e-12 <= s <= s1 + 1e-12:
        raise InputError("s", f"a fraction in face {face!r}'s contact range [{s0}, {s1}]", repr(s))
    if yaw is None:
        yaw = direction - f.push_angle
    offset = wrap_angle(direction - (yaw + f.push_angle))
    if abs(offset) > f.theta_b + 1e-12:
        raise InputError(
            "direction",
            f"a direction within theta_b = {f.theta_b:.4g} rad of face {face!r}'s push direction "
            f"{wrap_angle(yaw + f.push_angle):.4g} rad at yaw {yaw:.4g}",
            f"{direction:.4g} rad (offset {offset:.4g})",
        )
    pose0 = Pose2D(0.0, 0.0, yaw)
    n = pose0.rotate(f.normal)
    q = c + model.support(-n)
    p = f.point(float(s))
    x = q - pose0.rotate(p)
    return Contact(Pose2D(x[0], x[1], yaw), face, float(s), p, q, n, direction, offset)


@dataclass(frozen=True)
class PlatformContact:
    """Result of :func:`contact_on_platform`.

    Attributes:
        contact: the contact with the heading the Omni imposes, or None when unreachable.
        ik: inverse kinematics of the contact pose's tool centre point.
        in_cone: whether the desired direction lies in the face's cone at that heading.
    """

    contact: Contact | None
    ik: IKResult
    in_cone: bool


def contact_on_platform(
    tool: Tool,
    face: str,
    centre: ArrayLike,
    direction: float,
    platform: OmniPlatform,
    *,
    s: float | None = None,
    obj: ObjectModel | None = None,
    max_iter: int = 100,
) -> PlatformContact:
    """Contact pose whose heading is the one the Omni has when its tool is there.

    Solves ``yaw = heading(q1(x(yaw)))`` by fixed-point iteration from ``direction -
    push_angle`` (a contraction when the tool is small next to its distance from the joint-1 axis).
    The contact geometry holds exactly; ``in_cone`` tells whether ``direction`` is still pushable.
    """
    f = tool.face(face)
    c = check_array(centre, "centre", shape=(2,))
    yaw = float(direction) - f.push_angle
    ik = None
    for _ in range(max_iter):
        con = contact_pose(tool, face, c, yaw + f.push_angle, s=s, yaw=yaw, obj=obj)
        ik = inverse_kinematics(platform, con.pose.position)
        if not ik.reachable:
            return PlatformContact(None, ik, False)
        new = float(ik.heading)  # type: ignore[arg-type]
        if abs(wrap_angle(new - yaw)) < 1e-14:
            yaw = new
            break
        yaw = new
    else:
        raise InputError("max_iter", "enough iterations for the heading to converge", str(max_iter))
    con = contact_pose(tool, face, c, yaw + f.push_angle, s=s, yaw=yaw, obj=obj)
    offset = wrap_angle(float(direction) - (yaw + f.push_angle))
    inside = abs(offset) <= f.theta_b
    con = Contact(
        con.pose,
        face,
        con.s,
        con.tool_point,
        con.object_point,
        con.normal,
        float(direction),
        offset,
    )
    return PlatformContact(con, inverse_kinematics(platform, con.pose.position), inside)
