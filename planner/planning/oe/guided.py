"""A push sequence found by a best-first search over puck positions, for the ``qp`` fit to refine.

Where the scored candidates of :func:`~tooltransfer.planner.planning.oe.qp_variant.condense_qp` hold no
feasible sequence, the search here looks for one directly: from the start, straight steps of
``step`` [m] in directions of each face's admissible cone (the plan's narrowed friction cone
intersected with the tool file's cone, turned by the heading the Omni imposes with the contact at a
few places along the face), with the face held where the Omni reaches it and its tool outline clear
of the obstacles, the puck the safety margin from them; A* on the path length plus a price per face
change, to within ``step`` of the target. Its faces and the times of their changes (in proportion to
the path's length, over the universal path's duration) are then fitted by
:func:`~tooltransfer.planner.planning.oe.qp_variant.condense_sequence` with the path as reference,
which imposes every constraint of the ``qp`` variant; the search only proposes.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.face_frame import admissible_cone
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.qp_variant import condense_sequence
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.reach import reach_sector


@dataclass(frozen=True)
class GuidedPath:
    """A path the search found: puck positions (K, 2) [m] (start first, target last) and the face
    that pushes along each step (K - 1,)."""

    xy: NDArray[np.float64]
    faces: tuple[str, ...]

    def sequence(self, duration: float) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[str, ...],
                                                  tuple[float, ...]]:
        """``(t, ref, faces, switches)``: times (K,) [s] in proportion to the length over ``duration``
        [s], the reference path (K, 2) [m], the runs' faces and the times of their changes [s]."""
        seg = np.hypot(*np.diff(self.xy, axis=0).T)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        t = duration * s / s[-1]
        faces, switches = [self.faces[0]], []
        for k in range(1, len(self.faces)):
            if self.faces[k] != faces[-1]:
                faces.append(self.faces[k])
                switches.append(float(t[k]))
        return t, self.xy, tuple(faces), tuple(switches)


def _holds(setting: Setting, cone_half: float) -> list:
    """Per face that can push: ``(name, places, (lo, hi))``: the puck's centre (2,) [m] in the tool frame
    at contact places along the face, and its admissible cone [rad] (tool frame, shrunk by 2 %)."""
    out = []
    for f in setting.tool.faces:
        lo, hi = admissible_cone(f.normal_angle, f.push_angle, f.theta_b, cone_half)
        if hi <= lo:
            continue
        shrink = 0.02 * (hi - lo)
        places = [f.point(s) + setting.radius * f.normal for s in np.linspace(*f.contact_range, 5)]
        out.append((f.name, places, (lo + shrink, hi - shrink)))
    return out


def guided_path(setting: Setting, start: NDArray[np.float64], target: NDArray[np.float64], *,
                cone_fraction: float, step: float = 0.004, cell: float = 0.002, switch_price: float = 0.01,
                budget: int = 3000) -> GuidedPath | None:
    """A* from ``start`` to within ``step`` of ``target`` (module docstring), or None within ``budget``
    expansions. ``cone_fraction``: the share of the friction cone's half-angle the plan may use;
    ``switch_price`` [m]: the path length a face change is worth."""
    sec = reach_sector(setting.platform)
    bx, by = (float(v) for v in sec.centre)
    outline = np.asarray(setting.tool.outline.exterior.coords)
    obstacles = [o.polygon() if isinstance(o, Disc) else o for o in setting.obstacles]
    for o in obstacles:
        shapely.prepare(o)
    clear = setting.radius + max(setting.margin - 1e-5, 0.0) + 1e-4
    faces = _holds(setting, cone_fraction * setting.mechanics.friction_angle)

    def moves(p: NDArray[np.float64]) -> list[tuple[str, float]]:
        """(face, world direction) pairs the puck may take from ``p``."""
        dx, dy = p[0] - bx, p[1] - by
        r = math.hypot(dx, dy)
        out = []
        for name, places, (lo, hi) in faces:
            for c in places:
                o = D_TOOL - c[0]
                if r <= abs(o) + 1e-9:
                    continue
                v = math.sqrt(r * r - o * o)
                a = math.atan2(dy, dx) - math.atan2(o, v)
                q1 = math.remainder(a - sec.base_yaw, 2 * math.pi)
                if not (sec.u_range[0] <= v - c[1] <= sec.u_range[1] and sec.q1_range[0] <= q1 <= sec.q1_range[1]):
                    continue
                yaw = a - math.pi / 2
                if obstacles:
                    cy, sy = math.cos(yaw), math.sin(yaw)
                    body = shapely.Polygon((outline - c) @ np.array([[cy, sy], [-sy, cy]]) + p)
                    if any(shapely.intersects(o, body) for o in obstacles):
                        continue
                out += [(name, yaw + ang) for ang in (lo, 0.5 * (lo + hi), hi)]
                break
        return out

    def free(q: NDArray[np.float64]) -> bool:
        return all(shapely.distance(o, shapely.Point(q)) >= clear for o in obstacles)

    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    heap: list = [(float(np.hypot(*(target - start))), 0.0, 0, None)]
    nodes: list[tuple[NDArray[np.float64], int, str | None]] = [(start, -1, None)]
    seen: set = set()
    n = 0
    while heap and n < budget:
        _, g, k, _ = heapq.heappop(heap)
        p, _, came = nodes[k]
        key = (int(p[0] // cell), int(p[1] // cell), came)
        if key in seen:
            continue
        seen.add(key)
        n += 1
        if np.hypot(*(target - p)) <= step and came is not None:
            xy, fs = [target], [came]  # the last step, to the target, with the face that arrived
            while k >= 0:
                q, parent, face = nodes[k]
                xy.append(q)
                if face is not None:
                    fs.append(face)
                k = parent
            return GuidedPath(np.array(xy[::-1]), tuple(fs[::-1]))
        for name, ang in moves(p):
            q = p + step * np.array([math.cos(ang), math.sin(ang)])
            if (int(q[0] // cell), int(q[1] // cell), name) in seen or not free(q):
                continue
            g2 = g + step + (switch_price if came is not None and name != came else 0.0)
            nodes.append((q, k, name))
            heapq.heappush(heap, (g2 + float(np.hypot(*(target - q))), g2, len(nodes) - 1, name))
    return None


def condense_guided(t: NDArray[np.float64], universal: NDArray[np.float64], setting: Setting,
                    target: NDArray[np.float64] | None, options: QPOptions) -> PushPlan:
    """The ``qp`` variant's fallback when its scored candidates fail: the sequence of
    :func:`guided_path` fitted by :func:`condense_sequence` over the universal path's duration
    (``t`` (T,) [s], ``universal`` (T, 2) [m]); ``infeasible`` with the reason when either fails."""
    target = universal[-1] if target is None else target
    found = guided_path(setting, universal[0], target, cone_fraction=options.friction_cone_fraction)
    empty = np.zeros((0, 2))
    if found is None:
        return PushPlan("qp", "infeasible", np.zeros(0), empty, empty, universal,
                        reason="no path to the target within its expansions")
    tg, ref, faces, switches = found.sequence(float(t[-1] - t[0]))
    return condense_sequence(tg + t[0], ref, setting, target, faces, tuple(v + t[0] for v in switches), options)
