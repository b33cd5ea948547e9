"""Forward quasi-static simulation: a tool pose path in, the puck's path and the contact events out.

The tool (a polygon in the tool frame) follows the given poses ``(x, y, yaw)``; between two samples
the pose is interpolated linearly and the motion cut into substeps so that no outline point moves
more than ``max_step`` [m]. At each substep the tool moves with the puck held where it was; if the
outline then overlaps the disc by ``a`` (the pusher's advance along the contact normal), the puck
moves by the contact law of :mod:`tooltransfer.tools.pushing.mechanics` (sticking or sliding, with the pusher's
sideways displacement at the contact point), and is then pushed out along the contact normal of
its new place if a sliver of overlap remains (a corner, or a face turning with the heading). A puck
the tool does not press stays where it is (quasi-static: no inertia, no sliding on).

Everything is vectorised over a batch of independent runs of equal length (the identification
simulates all recorded pushes at once); :func:`simulate` is the one-run form.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.pushing.geometry import Outline
from tooltransfer.tools.pushing.mechanics import FREE, MODE_NAMES, SLIDE, STICK, PushMechanics, object_displacement
from tooltransfer.validation import check_array, check_positive

#: Default substep bound [m] on the motion of any outline point (0.1 mm: forward and inverse agree
#: to about 1e-3 mm per 50 mm of push, see ``tests/test_pushing.py``).
MAX_STEP = 1e-4
#: Overlap [m] below which a touching tool counts as in contact (for the recorded contact flags).
TOUCH_TOL = 1e-7


@dataclass(frozen=True)
class ContactEvent:
    """A change of contact along a run: at tool sample ``sample`` the contact became ``mode``
    (``"free"``, ``"stick"``, ``"slide"``) on ``feature`` (a face name, ``"edge i"`` or ``"vertex of
    edge i"``; ``None`` when free)."""

    sample: int
    mode: str
    feature: str | None


@dataclass(frozen=True)
class PushTrace:
    """What a forward simulation gives, at every tool sample (K of them).

    Attributes:
        object_xy: (K, 2) the puck's centre [m] (``object_xy[0]`` the start).
        mode: (K,) contact mode codes over the interval ending at the sample (0 free, 1 stick, 2 slide;
            the last substep's).
        edge: (K,) outline edge of the contact (-1 when free), at the sample.
        contact_tool: (K, 2) contact point in the tool frame [m] at the sample (NaN when free).
        face: (K,) the named face holding the contact, or None (free, or a contact off the faces).
        face_s: (K,) fraction along that face (NaN when not on a face).
        events: the contact changes, in order.
    """

    object_xy: NDArray[np.float64]
    mode: NDArray[np.int8]
    edge: NDArray[np.intp]
    contact_tool: NDArray[np.float64]
    face: tuple[str | None, ...]
    face_s: NDArray[np.float64]
    events: tuple[ContactEvent, ...] = field(default=())

    @property
    def final(self) -> NDArray[np.float64]:
        """The puck's final centre (2,) [m]."""
        return self.object_xy[-1]


def _face_of_edge(tool: Tool, outline: Outline) -> list[list[tuple[str, NDArray[np.float64], NDArray[np.float64]]]]:
    """For each outline edge, the named faces on it (name, start, end)."""
    out: list[list[tuple[str, NDArray[np.float64], NDArray[np.float64]]]] = [[] for _ in outline.start]
    for f in tool.faces:
        for m, (a, d) in enumerate(zip(outline.start, outline.direction, strict=True)):
            rel = np.vstack([f.start, f.end]) - a
            cross = np.abs(rel[:, 0] * d[1] - rel[:, 1] * d[0]) / np.sqrt(d @ d)
            u = rel @ d / (d @ d)
            if np.all(cross < 1e-9) and np.all(u > -1e-9) and np.all(u < 1 + 1e-9):
                out[m].append((f.name, f.start, f.end))
                break
    return out


def _rot(yaw: NDArray[np.float64]) -> NDArray[np.float64]:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def simulate_batch(
    tool: Tool, poses: ArrayLike, object_start: ArrayLike, radius: float, mech: PushMechanics, *,
    max_step: float = MAX_STEP,
) -> tuple[NDArray[np.float64], NDArray[np.int8], NDArray[np.intp], NDArray[np.float64]]:
    """Simulate ``B`` runs at once.

    Args:
        tool: the tool (its outline is the pusher).
        poses: (B, K, 3) tool poses ``x, y`` [m], ``yaw`` [rad] in the world, per run and sample.
        object_start: (B, 2) the puck's centres [m] at the first sample (not overlapping the tool).
        radius: the puck's radius [m].
        mech: the contact law's parameters.
        max_step: substep bound [m] on the motion of any outline point.
    Returns:
        ``object_xy`` (B, K, 2) [m], ``mode`` (B, K), ``edge`` (B, K) (-1 free) and ``contact``
        (B, K, 2) contact points in the tool frame [m] (NaN free).
    """
    if not isinstance(tool, Tool):
        raise InputError("tool", "a tooltransfer.tools.model.Tool", type(tool).__name__)
    if not isinstance(mech, PushMechanics):
        raise InputError("mech", "a PushMechanics", type(mech).__name__)
    p = check_array(poses, "poses", shape=(None, None, 3))
    b_n, k_n = p.shape[0], p.shape[1]
    c = check_array(object_start, "object_start", shape=(b_n, 2)).copy()
    r = check_positive(radius, "radius")
    h = check_positive(max_step, "max_step")
    outline = Outline.of(tool)
    reach = r + outline.radius + 1e-4
    xy = np.empty((b_n, k_n, 2))
    mode = np.zeros((b_n, k_n), dtype=np.int8)
    edge = np.full((b_n, k_n), -1, dtype=np.intp)
    contact = np.full((b_n, k_n, 2), np.nan)
    xy[:, 0] = c
    rows = np.arange(b_n)

    def touch(pose: NDArray[np.float64], centre: NDArray[np.float64]):
        rot = _rot(pose[:, 2])
        local = np.einsum("bji,bj->bi", rot, centre - pose[:, :2])  # R^T (c - x)
        near = outline.nearest(local)
        return rot, near, near.distance - r

    for k in range(k_n - 1):
        a, b = p[:, k], p[:, k + 1]
        move = np.max(np.hypot(*(b[:, :2] - a[:, :2]).T) + np.abs(b[:, 2] - a[:, 2]) * outline.radius)
        n_sub = max(1, int(np.ceil(move / h)))
        near_any = np.min(np.hypot(*(c - a[:, :2]).T) - move) <= reach
        if not near_any:
            xy[:, k + 1] = c
            continue
        last_mode = np.zeros(b_n, dtype=np.int8)
        last_edge = np.full(b_n, -1, dtype=np.intp)
        last_pt = np.full((b_n, 2), np.nan)
        prev = a
        for j in range(1, n_sub + 1):
            pose = a + (j / n_sub) * (b - a)
            rot, near, gap = touch(pose, c)
            push = gap < 0.0
            if np.any(push):
                rot_prev = _rot(prev[:, 2])
                q = near.point
                moved = (pose[:, :2] + np.einsum("bij,bj->bi", rot, q)) - (
                    prev[:, :2] + np.einsum("bij,bj->bi", rot_prev, q))
                n_w = np.einsum("bij,bj->bi", rot, near.normal)
                t_w = np.stack([-n_w[:, 1], n_w[:, 0]], axis=1)
                slip = np.einsum("bi,bi->b", moved, t_w)
                d, m = object_displacement(np.where(push, -gap, 0.0), np.where(push, slip, 0.0), n_w, mech)
                c = c + d
                for _ in range(3):  # a sliver of overlap left by a turning normal: out along the new one
                    rot, near2, gap2 = touch(pose, c)
                    deep = gap2 < -1e-13
                    if not np.any(deep):
                        break
                    c = c + np.where(deep, -gap2, 0.0)[:, None] * np.einsum("bij,bj->bi", rot, near2.normal)
                last_mode = np.where(push, m, last_mode)
                last_edge = np.where(push, near.edge, last_edge)
                last_pt = np.where(push[:, None], near.point, last_pt)
            touching = (gap < TOUCH_TOL) & ~push
            last_edge = np.where(touching & (last_mode == FREE), near.edge, last_edge)
            prev = pose
        xy[:, k + 1] = c
        mode[:, k + 1] = last_mode
        edge[:, k + 1] = last_edge
        contact[:, k + 1] = last_pt
    del rows
    return xy, mode, edge, contact


_Nearest = Callable[[float, float], tuple[float, int, float, float, float, float]]


def _outline_queries(outline: Outline, r: float) -> _Nearest:
    """``nearest(lx, ly)``: for a disc of radius ``r`` centred at the tool-frame point, ``(gap, edge, qx,
    qy, nx, ny)``: its gap to the outline [m] (negative: overlapping), the nearest outline point's edge
    and place, and the contact normal (tool frame; the edge's normal when the centre is inside)."""
    segs = [(float(a[0]), float(a[1]), float(d[0]), float(d[1]), float(l2), m)
            for m, (a, d, l2) in enumerate(zip(outline.start, outline.direction, outline.length2, strict=True))]
    normals = [(float(n[0]), float(n[1])) for n in outline.normal]
    sides = [(ax, ay, dx, dy) for ax, ay, dx, dy, _, _ in segs]
    sqrt, inf = math.sqrt, math.inf

    def inside(lx: float, ly: float) -> bool:
        """Whether the tool-frame point lies inside the outline (crossing number; a nearest point at a
        vertex says nothing about the side by one edge's normal)."""
        odd = False
        for ax, ay, dx, dy in sides:
            if (ay > ly) != (ay + dy > ly) and lx < ax + (ly - ay) * dx / dy:
                odd = not odd
        return odd

    def nearest(lx: float, ly: float) -> tuple[float, int, float, float, float, float]:
        best, bm, bqx, bqy = inf, -1, 0.0, 0.0
        for ax, ay, dx, dy, l2, m in segs:
            u = ((lx - ax) * dx + (ly - ay) * dy) / l2
            u = 0.0 if u < 0.0 else (1.0 if u > 1.0 else u)
            qx, qy = ax + u * dx, ay + u * dy
            d2 = (lx - qx) ** 2 + (ly - qy) ** 2
            if d2 < best:
                best, bm, bqx, bqy = d2, m, qx, qy
        dist = sqrt(best)
        if dist > 1e-15:
            nx, ny = (lx - bqx) / dist, (ly - bqy) / dist
            if dist < r and inside(lx, ly):  # the centre inside the outline: out along the edge's normal
                (nx, ny), dist = normals[bm], -dist
        else:
            nx, ny = normals[bm]
        return dist - r, bm, bqx, bqy, nx, ny

    return nearest


def _run_scalar(
    tool: Tool, p: NDArray[np.float64], start: NDArray[np.float64], r: float, mech: PushMechanics, h: float,
) -> tuple[NDArray[np.float64], NDArray[np.int8], NDArray[np.intp], NDArray[np.float64]]:
    """:func:`simulate_batch` for one run in scalar arithmetic (faster than the batch code at B = 1:
    no array overhead per substep; the samples gathered in lists, the arrays filled once)."""
    outline = Outline.of(tool)
    nearest = _outline_queries(outline, r)
    reach = r + outline.radius + 1e-4
    mu, kappa = mech.mu, mech.kappa
    cos, sin = math.cos, math.sin
    k_n = p.shape[0]
    xy = np.empty((k_n, 2))
    mode = np.zeros(k_n, dtype=np.int8)
    edge = np.full(k_n, -1, dtype=np.intp)
    contact = np.full((k_n, 2), np.nan)
    cx, cy = float(start[0]), float(start[1])
    xy[0] = cx, cy
    rows = p.tolist()
    centres, modes, edges, contacts = [], [], [], []  # from sample 1 on
    for k in range(k_n - 1):
        ax, ay, ayaw = rows[k]
        bx, by, byaw = rows[k + 1]
        move = math.hypot(bx - ax, by - ay) + abs(byaw - ayaw) * outline.radius
        pc, ps = cos(ayaw), sin(ayaw)  # of the pose before each substep's
        ex, ey = cx - ax, cy - ay
        if math.hypot(ex, ey) - move > reach or nearest(pc * ex + ps * ey, -ps * ex + pc * ey)[0] > move + 1e-9:
            centres.append((cx, cy))  # no outline point moves far enough to reach the puck in this interval
            modes.append(FREE)
            edges.append(-1)
            contacts.append((math.nan, math.nan))
            continue
        n_sub = max(1, math.ceil(move / h))
        last_mode, last_edge, lqx, lqy = FREE, -1, math.nan, math.nan
        px, py = ax, ay
        for j in range(1, n_sub + 1):
            f = j / n_sub
            x, y, yaw = ax + f * (bx - ax), ay + f * (by - ay), ayaw + f * (byaw - ayaw)
            co, si = cos(yaw), sin(yaw)
            ex, ey = cx - x, cy - y
            gap, m, qx, qy, nx, ny = nearest(co * ex + si * ey, -si * ex + co * ey)
            if gap < 0.0:
                nx, ny = co * nx - si * ny, si * nx + co * ny  # the normal in the world
                mx = (x + co * qx - si * qy) - (px + pc * qx - ps * qy)
                my = (y + si * qx + co * qy) - (py + ps * qx + pc * qy)
                a, slip = -gap, -ny * mx + nx * my
                if abs(slip) <= mu * kappa * a:
                    lat, last_mode = slip / kappa, STICK
                else:
                    lat, last_mode = math.copysign(mu * a, slip), SLIDE
                cx += a * nx - lat * ny
                cy += a * ny + lat * nx
                for _ in range(3):  # a sliver of overlap left by a turning normal: out along the new one
                    ex, ey = cx - x, cy - y
                    g2, m, qx, qy, nx2, ny2 = nearest(co * ex + si * ey, -si * ex + co * ey)
                    if g2 >= -1e-13:
                        break
                    cx, cy = cx - g2 * (co * nx2 - si * ny2), cy - g2 * (si * nx2 + co * ny2)
                last_edge, lqx, lqy = m, qx, qy  # where the contact is once the object has moved
            px, py, pc, ps = x, y, co, si
        centres.append((cx, cy))
        modes.append(last_mode)
        edges.append(last_edge)
        contacts.append((lqx, lqy))
    if k_n > 1:
        xy[1:], mode[1:], edge[1:], contact[1:] = centres, modes, edges, contacts
    return xy, mode, edge, contact


def _run_checked(
    tool: Tool, poses: ArrayLike, object_start: ArrayLike, radius: float, mech: PushMechanics, max_step: float,
) -> tuple[NDArray[np.float64], tuple[NDArray[np.float64], NDArray[np.int8], NDArray[np.intp], NDArray[np.float64]]]:
    """The arguments of :func:`simulate` checked, the poses as an array, and :func:`_run_scalar` on them."""
    if not isinstance(tool, Tool):
        raise InputError("tool", "a tooltransfer.tools.model.Tool", type(tool).__name__)
    if not isinstance(mech, PushMechanics):
        raise InputError("mech", "a PushMechanics", type(mech).__name__)
    p = check_array(poses, "poses", shape=(None, 3))
    start = check_array(object_start, "object_start", shape=(2,))
    return p, _run_scalar(tool, p, start, check_positive(radius, "radius"), mech, check_positive(max_step, "max_step"))


def object_path(
    tool: Tool, poses: ArrayLike, object_start: ArrayLike, radius: float, mech: PushMechanics, *,
    max_step: float = MAX_STEP,
) -> NDArray[np.float64]:
    """The puck's path (K, 2) [m] of :func:`simulate` (the same numbers), without naming the faces
    and the contact events: for a replay that compares paths only (checking a plan file)."""
    return _run_checked(tool, poses, object_start, radius, mech, max_step)[1][0]


def simulate(
    tool: Tool, poses: ArrayLike, object_start: ArrayLike, radius: float, mech: PushMechanics, *,
    max_step: float = MAX_STEP,
) -> PushTrace:
    """Simulate one run: tool poses (K, 3) [m, m, rad], the puck from ``object_start`` (2,) [m].

    See :func:`simulate_batch`; the result names the faces the contact lies on and lists the
    contact events.
    """
    p, (xy, mode, edge, contact) = _run_checked(tool, poses, object_start, radius, mech, max_step)
    outline = Outline.of(tool)
    faces_on = _face_of_edge(tool, outline)
    names: list[str | None] = []
    s = np.full(p.shape[0], np.nan)
    for k in range(p.shape[0]):
        name = None
        if mode[k] != FREE and edge[k] >= 0:
            for fname, fa, fb in faces_on[int(edge[k])]:
                d = fb - fa
                u = float((contact[k] - fa) @ d / (d @ d))
                if -1e-9 <= u <= 1 + 1e-9:
                    name, s[k] = fname, u
                    break
        names.append(name)
    events: list[ContactEvent] = []
    prev: tuple[int, str | None] | None = None
    for k in range(1, p.shape[0]):
        m = int(mode[k])
        feat = None
        if m != FREE:
            feat = names[k] or f"edge {int(edge[k])}"
        if prev != (m, feat):
            events.append(ContactEvent(k, MODE_NAMES[m], feat))
            prev = (m, feat)
    return PushTrace(xy, mode, edge, contact, tuple(names), s, tuple(events))
