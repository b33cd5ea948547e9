"""A switch to plan (the domain problem): tool, the two contacts, the object and its pose, obstacles,
the Omni; and its contact poses (paper section III.B step 5: "confirm the starting contact
positions and select the potential contact points on the object and the tool").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.errors import InfeasibleError, InputError
from tooltransfer.tools.contact import Contact, contact_pose
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, DiscObject, ObjectModel, Obstacle, PolygonObject
from tooltransfer.tools.omni.heading import heading_scalar
from tooltransfer.tools.omni.ik import inverse_kinematics
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import Pose2D
from tooltransfer.validation import check_array, check_positive


@dataclass(frozen=True)
class SwitchTask:
    """A switch from ``face_from`` to ``face_to`` of ``tool`` round the resting object.

    Attributes:
        tool: the tool.
        face_from, face_to: face names (may be equal: a switch of the contact point along one face).
        centre: shape (2,), the object's centre (reference point) in the world [m].
        s_from, s_to: fractions along the faces of the tool contact points (None: middle of the
            contact range).
        obj: the object model (default the paper's 17.5 mm disc; a convex :class:`PolygonObject`).
        obstacles: discs or shapely polygons (world) the tool must keep clear of.
        platform: the Omni (default: at the origin, carrying ``tool``'s ``a_t``).
        duration: switch duration [s] (None: the skill's demonstrated duration).
    """

    tool: Tool
    face_from: str
    face_to: str
    centre: NDArray[np.float64]
    s_from: float | None = None
    s_to: float | None = None
    obj: ObjectModel = field(default_factory=DiscObject)
    obstacles: tuple[Obstacle, ...] = ()
    platform: OmniPlatform | None = None
    duration: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.tool, Tool):
            raise InputError("tool", "a tooltransfer.tools.model.Tool", type(self.tool).__name__)
        for f in (self.face_from, self.face_to):
            self.tool.face(f)  # UnknownFaceError lists the faces
        object.__setattr__(self, "centre", check_array(self.centre, "centre", shape=(2,)))
        if not isinstance(self.obj, DiscObject | PolygonObject):
            raise InputError("obj", "a DiscObject or PolygonObject", type(self.obj).__name__)
        obs = tuple(self.obstacles)
        for i, o in enumerate(obs):
            if not isinstance(o, Disc | shapely.Polygon):
                raise InputError(f"obstacles[{i}]", "a Disc or a shapely Polygon", type(o).__name__)
        object.__setattr__(self, "obstacles", obs)
        if self.platform is None:
            object.__setattr__(self, "platform", OmniPlatform(a_t=self.tool.a_t))
        elif not isinstance(self.platform, OmniPlatform):
            raise InputError("platform", "an OmniPlatform", type(self.platform).__name__)
        if self.duration is not None:
            object.__setattr__(self, "duration", check_positive(self.duration, "duration"))
        if self.face_from == self.face_to and self.s_from == self.s_to:
            raise InputError("s_to", "a different contact point when the face stays the same", repr(self.s_to))

    @property
    def omni(self) -> OmniPlatform:
        """The platform (never None after construction)."""
        assert self.platform is not None  # set in __post_init__
        return self.platform

    @property
    def shape(self) -> Disc | shapely.Polygon:
        """The placed object (world)."""
        if isinstance(self.obj, DiscObject):
            return Disc(self.centre, self.obj.radius)
        return self.obj.at(self.centre)

    def contact(self, which: str) -> Contact:
        """The contact pose ``"from"`` or ``"to"`` with the Omni's heading.

        Raises:
            InfeasibleError: the Omni cannot reach it (family ``reach``; the reason names the pose).
        """
        face, s = (self.face_from, self.s_from) if which == "from" else (self.face_to, self.s_to)
        f = self.tool.face(face)
        # the heading fixed point yaw = heading(x(yaw)) of tooltransfer.tools.contact.contact_on_platform, with the
        # closed-form heading (a contraction: |p| / |x - b| << 1), then the exact contact and the IK
        s0, s1 = f.contact_range
        px, py = (float(v) for v in f.point(0.5 * (s0 + s1) if s is None else float(s)))
        nx, ny = (float(v) for v in f.normal)
        cx, cy = (float(v) for v in self.centre)
        disc = self.obj.radius if isinstance(self.obj, DiscObject) else None
        yaw = heading_scalar(self.omni, cx, cy)
        done, prev = False, yaw
        for _ in range(60):
            c, sn = math.cos(yaw), math.sin(yaw)
            wx, wy = c * nx - sn * ny, sn * nx + c * ny  # the face normal in the world
            if disc is not None:  # the disc's support point along -n, without arrays
                qx, qy = cx - disc * wx / math.hypot(wx, wy), cy - disc * wy / math.hypot(wx, wy)
            else:
                qx, qy = (float(v) for v in self.centre + self.obj.support(np.array([-wx, -wy])))
            new = heading_scalar(self.omni, qx - (c * px - sn * py), qy - (sn * px + c * py))
            done = abs(new - yaw) < 1e-14
            prev, yaw = yaw, new
            if done:
                break
        if done or disc is not None:
            con = contact_pose(self.tool, face, self.centre, yaw + f.push_angle, s=s, yaw=yaw, obj=self.obj)
        else:
            con = self._flush_contact(which, face, prev, yaw)
        ik = inverse_kinematics(self.omni, con.pose.position)
        if not ik.reachable:
            label = "start" if which == "from" else "end"
            raise InfeasibleError("switch", ["reach"], f"{label} contact pose ({face!r} on the object at "
                                  f"{np.round(self.centre, 4).tolist()}) unreachable: {ik.reason}: {ik.detail}")
        return con

    def _flush_contact(self, which: str, face: str, yaw_a: float, yaw_b: float) -> Contact:
        """The contact when the heading iteration alternates between two vertices of a polygonal
        object (``yaw_a``, ``yaw_b`` [rad] its last two iterates): the face then lies flush on the
        edge between them, at the yaw that makes it parallel, and the contact point slides along the
        edge to where the Omni's heading is that yaw (a root in the edge parameter, by bisection).
        Raises :class:`InfeasibleError` when no point of the edge gives that heading."""
        import scipy.optimize

        f = self.tool.face(face)
        s0, s1 = f.contact_range
        s = self.s_from if which == "from" else self.s_to
        s = 0.5 * (s0 + s1) if s is None else float(s)
        p = f.point(s)
        assert isinstance(self.obj, PolygonObject)  # discs always settle

        def normal(yaw: float) -> NDArray[np.float64]:  # the face's normal in the world
            return Pose2D(0.0, 0.0, yaw).rotate(f.normal)

        va, vb = (np.asarray(self.obj.support(-normal(y)), dtype=np.float64) for y in (yaw_a, yaw_b))
        label = "start" if which == "from" else "end"
        edge = vb - va
        if float(np.hypot(*edge)) < 1e-12:
            raise InfeasibleError("switch", ["contact"], f"the {label} contact heading did not settle ({face!r})")
        # the face's world normal must point into the object, against the edge's outward normal
        out = np.array([edge[1], -edge[0]]) / float(np.hypot(*edge))
        if out @ (0.5 * (va + vb)) < 0:
            out = -out
        yaw = math.atan2(-out[1], -out[0]) - math.atan2(f.normal[1], f.normal[0])
        rp = Pose2D(0.0, 0.0, yaw).rotate(p)

        def gap(t: float) -> float:
            x = self.centre + va + t * edge - rp
            return math.remainder(heading_scalar(self.omni, float(x[0]), float(x[1])) - yaw, 2 * math.pi)

        if gap(0.0) * gap(1.0) > 0:
            raise InfeasibleError("switch", ["contact"], (
                f"the {label} contact ({face!r} flush on an edge of the object) has no point where the "
                "Omni's heading keeps the face parallel to the edge"))
        t = scipy.optimize.brentq(gap, 0.0, 1.0, xtol=1e-15)
        q = self.centre + va + t * edge
        x = q - rp
        return Contact(Pose2D(float(x[0]), float(x[1]), yaw), face, s, p, q, normal(yaw), yaw + f.push_angle, 0.0)
