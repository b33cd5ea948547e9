"""Inverse push model, for planning: the tool motion that makes a face push the puck along a wanted path.

A straight face touches the disc (radius ``R``) at the foot of the perpendicular from its centre,
so with the contact at arc length ``s`` along the face (from its ``start``, direction ``e``, outward
normal ``n``; tool frame) the puck's centre sits at ``c_T(s) = start + s e + R n`` in the tool
frame, and the tool pose follows from the centre ``c`` and the heading ``psi`` the Omni imposes
there: ``x_tool = c - R(psi) c_T(s)`` with ``psi = heading(x_tool)``
(:func:`tooltransfer.tools.omni.heading.centre_path`).

While the contact sticks, the tool's contact point moves with the puck's rim point: the same normal
speed as the centre and ``kappa = 1 + 1/c^2`` times its sideways speed (:mod:`tooltransfer.tools.pushing.mechanics`).
In the tool frame the contact therefore rolls along the face,

    ds/dt = -(1/c^2) (v_c . e_w) - sigma R dpsi/dt,      sigma = e . (J n) = +-1,

where ``e_w`` is the face direction in the world: the centre's sideways travel moves it ``1/c^2``
times as far the other way, and a turn of the heading rolls the disc along the face by ``R`` per
radian. Given the centre's path and where the contact starts, ``s`` follows by integration (the
trapezoidal rule in the heading) and, with it, the tool poses. The path is admissible when every
step lies in the friction cone about the contact normal (the contact sticks) and ``s`` stays on
the face.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.omni.heading import newton_centres
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pushing.mechanics import PushMechanics, cone_margin, perp
from tooltransfer.validation import check_array, check_positive

#: Steps of the object shorter than this [m] are not judged against the friction cone (a path
#: standing still at a switch has steps of nanometres in arbitrary directions).
STILL = 1e-7

Coords = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
"""Tool poses as their coordinates ``x, y`` [m] and ``yaw`` [rad], each (K,)."""


@dataclass(frozen=True)
class FaceGeometry:
    """A face in the tool frame, for the inverse model.

    Attributes:
        name: face name.
        start: (2,) face start [m]; direction: (2,) unit vector along it; length: [m].
        normal: (2,) outward unit normal; sigma: ``direction . (J normal)`` (+1 or -1).
        lo, hi: usable arc lengths [m] (the face's contact range).
    """

    name: str
    start: NDArray[np.float64]
    direction: NDArray[np.float64]
    length: float
    normal: NDArray[np.float64]
    sigma: float
    lo: float
    hi: float

    @classmethod
    def of(cls, tool: Tool, face: str) -> FaceGeometry:
        f = tool.face(face)
        e = (f.end - f.start) / f.length
        sigma = float(np.sign(e @ perp(f.normal)))
        s0, s1 = f.contact_range
        return cls(face, f.start.copy(), e, f.length, f.normal.copy(), sigma, s0 * f.length, s1 * f.length)

    def centre_in_tool(self, s: ArrayLike, radius: float) -> NDArray[np.float64]:
        """The puck's centre (K, 2) [m] in the tool frame with the contact at arc lengths ``s`` (K,)."""
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        return self.start + s[:, None] * self.direction + radius * self.normal


@dataclass(frozen=True)
class FacePush:
    """The tool motion realising a push (K samples).

    Attributes:
        face: the face; tool_pose: (K, 3) ``x, y`` [m] and ``yaw`` [rad].
        s: (K,) arc length [m] of the contact along the face (from its start).
        normal: (K, 2) the contact normal in the world (into the puck).
        cone_margin: (K-1,) ``atan(mu) - |phi_c|`` [rad] of each step (negative: outside the cone,
            the contact would slide; ``-pi``: a step that pulls).
        edge_margin: least distance [m] of the contact from the ends of the face's usable range
            (negative: it leaves the face).
    """

    face: FaceGeometry
    tool_pose: NDArray[np.float64]
    s: NDArray[np.float64]
    normal: NDArray[np.float64]
    cone_margin: NDArray[np.float64]

    @property
    def edge_margin(self) -> float:
        return float(min(np.min(self.s - self.face.lo), np.min(self.face.hi - self.s)))

    @property
    def sticks(self) -> bool:
        """Whether every step that moves the puck lies inside the friction cone."""
        return bool(np.all(self.cone_margin >= 0.0))


def _poses(face: FaceGeometry, c: NDArray[np.float64], s: NDArray[np.float64], radius: float,
           platform: OmniPlatform | None, yaw: NDArray[np.float64] | None, guess: Coords | None = None) -> Coords:
    """The tool poses with the puck at ``c`` (K, 2) [m] and the contact at ``s`` (K,) [m] along ``face``;
    ``guess``: poses near them (the tool's centres Newton starts from)."""
    ct = face.centre_in_tool(s, radius)
    if platform is not None:
        if guess is None:
            start = c - ct
            return newton_centres(platform, c[:, 0], c[:, 1], ct[:, 0], ct[:, 1], start[:, 0], start[:, 1])
        return newton_centres(platform, c[:, 0], c[:, 1], ct[:, 0], ct[:, 1], guess[0], guess[1])
    assert yaw is not None
    co, si = np.cos(yaw), np.sin(yaw)
    xy = c - np.column_stack([co * ct[:, 0] - si * ct[:, 1], si * ct[:, 0] + co * ct[:, 1]])
    return xy[:, 0], xy[:, 1], yaw


def _inputs(tool: Tool, face: str, object_xy: ArrayLike, radius: float, platform: OmniPlatform | None,
            yaw: ArrayLike | None) -> tuple[FaceGeometry, NDArray[np.float64], float, NDArray[np.float64] | None]:
    """The checked arguments of :func:`push_tool_path`: the face, the object's path (K, 2) [m], the
    radius [m] and the yaws (K,) [rad] or None."""
    if (platform is None) == (yaw is None):
        raise InputError("platform", "exactly one of platform and yaw")
    g = FaceGeometry.of(tool, face)
    c = check_array(object_xy, "object_xy", shape=(None, 2))
    if c.shape[0] < 2:
        raise InputError("object_xy", "at least 2 samples", f"{c.shape[0]}")
    r = check_positive(radius, "radius")
    return g, c, r, None if yaw is None else check_array(yaw, "yaw", shape=(c.shape[0],))


def _roll(g: FaceGeometry, c: NDArray[np.float64], r: float, mech: PushMechanics, s0: float,
          platform: OmniPlatform | None, yaw: NDArray[np.float64] | None,
          iters: int) -> tuple[NDArray[np.float64], Coords | None]:
    """The contact's arc lengths (K,) [m] along ``g`` as the object follows ``c`` (K, 2) [m] from
    ``s0`` [m]: the rolling law integrated at the tool's headings with the contact at the previous arc
    lengths, again until they move less than 1 nm (at most ``iters`` times); and the tool poses the
    last integration was made at, where Newton starts for the poses at the returned arc lengths (None
    when ``iters`` is 0)."""
    dc = np.diff(c, axis=0)
    s = np.full(c.shape[0], float(s0))
    pose = None
    rolled = np.zeros(c.shape[0])  # the contact's travel from s0 [m]
    for _ in range(iters):
        pose = _poses(g, c, s, r, platform, yaw, pose)
        psi = pose[2]
        mid = 0.5 * (psi[:-1] + psi[1:])
        cm, sm = np.cos(mid), np.sin(mid)
        e_w = np.column_stack([cm * g.direction[0] - sm * g.direction[1], sm * g.direction[0] + cm * g.direction[1]])
        step = -mech.rolling * np.einsum("ij,ij->i", dc, e_w) - g.sigma * r * np.diff(psi)
        np.cumsum(step, out=rolled[1:])
        new = float(s0) + rolled
        done = float(np.abs(new - s).max()) < 1e-9
        s = new
        if done:
            break
    return s, pose


def push_tool_path(
    tool: Tool, face: str, object_xy: ArrayLike, radius: float, mech: PushMechanics, s0: float, *,
    platform: OmniPlatform | None = None, yaw: ArrayLike | None = None, iters: int = 6,
) -> FacePush:
    """The tool poses that push the puck along ``object_xy`` (K, 2) [m] with ``face``, the contact
    starting at arc length ``s0`` [m] along the face, sticking throughout.

    The heading comes from ``platform`` (the Omni's, a function of the tool's position) or is given
    as ``yaw`` (K,) [rad]; exactly one of them.
    """
    g, c, r, yaw_a = _inputs(tool, face, object_xy, radius, platform, yaw)
    s, guess = _roll(g, c, r, mech, s0, platform, yaw_a, iters)
    pose = np.column_stack(_poses(g, c, s, r, platform, yaw_a, guess))
    psi = pose[:, 2]
    cp, sp = np.cos(psi), np.sin(psi)
    n_w = np.column_stack([cp * g.normal[0] - sp * g.normal[1], sp * g.normal[0] + cp * g.normal[1]])
    n_mid = 0.5 * (n_w[:-1] + n_w[1:])
    n_mid /= np.linalg.norm(n_mid, axis=1)[:, None]
    dc = np.diff(c, axis=0)
    margin = cone_margin(dc, n_mid, mech)
    still = np.hypot(dc[:, 0], dc[:, 1]) < STILL
    return FacePush(g, pose, s, n_w, np.where(still, mech.friction_angle, margin))


def contact_path(
    tool: Tool, face: str, object_xy: ArrayLike, radius: float, mech: PushMechanics, s0: float, *,
    platform: OmniPlatform | None = None, yaw: ArrayLike | None = None, iters: int = 6,
) -> NDArray[np.float64]:
    """The contact's arc lengths (K,) [m] along ``face`` of :func:`push_tool_path` (same arguments, the
    same values: its ``s``) without the tool poses and the friction cone's margins there."""
    g, c, r, yaw_a = _inputs(tool, face, object_xy, radius, platform, yaw)
    return _roll(g, c, r, mech, s0, platform, yaw_a, iters)[0]
