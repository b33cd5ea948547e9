"""Contacts a round object can make with a tool outline (docs/design.md section 13).

Tool frame and units as in :mod:`tooltransfer.tools.model` (metres, radians from +x, counter-clockwise).
For the outline's counter-clockwise ring, edge ``i`` runs from vertex ``i`` to vertex ``i + 1`` with
unit tangent ``t`` and outward normal ``n = (t_y, -t_x)``. A disc of radius ``R`` touches the edge
at ``p = a + s t`` (``0 <= s <= L``) when its centre is ``c(s) = p + R n``; the contact is usable
when that disc does not overlap the rest of the outline, i.e. ``dist(c(s), outline) >= R``. The
usable centres are the part of the centre line ``a + R n .. b + R n`` outside the outline grown by
``R`` (shapely's buffer with :data:`QUAD_SEGS` segments per quarter circle: its round joins lie
within ``R (1 - cos(pi / (4 QUAD_SEGS)))``, 1.3 um for ``R`` = 17.5 mm, of the true offset), and its
ends are then moved by bisection on shapely's exact distance until the disc there clears the outline
(penetration below 1e-14 m).

* An **edge contact** is the longest usable interval of an edge: its outward normal, its friction
  cone ``|phi| <= atan(mu)`` about the normal (section 10: the object's centre moves inside it
  whatever the tool does), and the sideways travel of the object one contact carries: the contact
  rolls ``1/c^2`` times the object's sideways travel along the face, so an interval of length ``l``
  carries ``l c^2``.
* A **vertex contact** is a convex vertex used as a point pusher: the contact normal joins the
  vertex to the object's centre and may point anywhere between the two adjacent edges' normals
  (where the disc clears the rest of the outline). A run of short facets approximating an arc (a
  rounded head) is a row of such vertices and short edges. The planner's faces are straight
  segments, so vertex contacts are reported and drawn but not planned with.

With an :class:`~tooltransfer.tools.omni.platform.OmniPlatform`, each edge contact also carries the
world directions it can push in across the Omni's reach (the heading follows the waist:
``yaw = base_yaw + q1 - pi/2``), and whether the Omni can push with it at all (the object's centre
must lie beyond the arm's axis: :class:`tooltransfer.planner.planning.oe.face_frame.FaceFrame`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.errors import InputError

#: Segments per quarter circle of the grown outline (see the module docstring for its error).
QUAD_SEGS = 64
#: Relative shrink of the growth radius, so that the centre line of the touching edge itself
#: (at exactly ``R``) is not counted as overlapping.
GROW_SHRINK = 1e-6
#: Tolerance [m] of the sampled vertex-contact check; EXACT_TOL: of the usable intervals' ends (rounding only).
CHECK_TOL = 5e-6
EXACT_TOL = 1e-14


@dataclass(frozen=True)
class EdgeContact:
    """The usable part of one straight edge (tool frame).

    Attributes:
        edge: index of the edge in the counter-clockwise ring (vertex ``edge`` to ``edge + 1``).
        start, end: shape (2,), the whole edge's end points [m].
        contact_range: fractions ``(s0, s1)`` of the edge where the object can touch it.
        normal: shape (2,), outward unit normal.
        friction_half: half-angle ``atan(mu)`` [rad] of the friction cone about the normal.
        travel: sideways travel [m] of the object one contact carries, ``(s1 - s0) L c^2``.
        world_directions: ``(lo, hi)`` [rad], world push directions across the Omni's reach, or
            None without a platform.
        on_platform: whether the Omni can push with this contact (True without a platform).
    """

    edge: int
    start: NDArray[np.float64]
    end: NDArray[np.float64]
    contact_range: tuple[float, float]
    normal: NDArray[np.float64]
    friction_half: float
    travel: float
    world_directions: tuple[float, float] | None = None
    on_platform: bool = True

    @property
    def name(self) -> str:
        """Generated face name, ``edge_<index>``."""
        return f"edge_{self.edge}"

    @property
    def length(self) -> float:
        """Length of the whole edge [m]."""
        return float(np.hypot(*(self.end - self.start)))

    @property
    def usable_length(self) -> float:
        """Length [m] of the usable part."""
        return (self.contact_range[1] - self.contact_range[0]) * self.length

    @property
    def normal_angle(self) -> float:
        """Angle [rad] of the outward normal."""
        return float(np.arctan2(self.normal[1], self.normal[0]))


@dataclass(frozen=True)
class VertexContact:
    """A convex vertex used as a point pusher (tool frame).

    Attributes:
        vertex: index of the vertex in the counter-clockwise ring.
        point: shape (2,), the vertex [m].
        normals: ``(lo, hi)`` [rad], counter-clockwise range of contact normal angles for which the
            object clears the rest of the outline (between the adjacent edges' normals).
        friction_half: half-angle ``atan(mu)`` [rad] of the friction cone about each normal.
    """

    vertex: int
    point: NDArray[np.float64]
    normals: tuple[float, float]
    friction_half: float

    @property
    def name(self) -> str:
        """Generated name, ``vertex_<index>``."""
        return f"vertex_{self.vertex}"


def ring_of(outline: shapely.Polygon) -> NDArray[np.float64]:
    """Vertices (N, 2) [m] of ``outline``'s exterior, counter-clockwise, without the closing repeat."""
    ccw = shapely.geometry.polygon.orient(outline, sign=1.0)
    return np.asarray(ccw.exterior.coords, dtype=np.float64)[:-1]


def _intervals(line: shapely.LineString, grown: shapely.Polygon) -> list[tuple[float, float]]:
    """Parameter intervals (fractions along ``line``) of the parts of ``line`` outside ``grown``."""
    free = line.difference(grown)
    parts = list(getattr(free, "geoms", [free])) if not free.is_empty else []
    total = line.length
    out = []
    for g in parts:
        if isinstance(g, shapely.LineString) and g.length > 0:
            ends = [line.project(shapely.Point(c)) / total for c in (g.coords[0], g.coords[-1])]
            out.append((min(ends), max(ends)))
    return sorted(out)


def edge_contacts(outline: shapely.Polygon, radius: float, friction: float, c: float,
                  min_length: float) -> list[EdgeContact]:
    """Every edge whose usable part is at least ``min_length`` [m] long (see the module docstring)."""
    ring = ring_of(outline)
    grown = outline.buffer(radius * (1.0 - GROW_SHRINK), quad_segs=QUAD_SEGS)
    half = float(np.arctan(friction))
    out = []
    for i in range(len(ring)):
        a, b = ring[i], ring[(i + 1) % len(ring)]
        e = b - a
        length = float(np.hypot(*e))
        if length < max(min_length, 1e-12):
            continue
        t = e / length
        n = np.array([t[1], -t[0]])
        line = shapely.LineString([a + radius * n, b + radius * n])
        spans = [(s0, s1) for s0, s1 in _intervals(line, grown) if (s1 - s0) * length >= min_length]
        if not spans:
            continue
        s0, s1 = max(spans, key=lambda r: r[1] - r[0])
        def clear(s: float, a: NDArray[np.float64] = a, e: NDArray[np.float64] = e,
                  n: NDArray[np.float64] = n) -> bool:
            return bool(outline.distance(shapely.Point(a + s * e + radius * n)) >= radius - EXACT_TOL)

        mid = 0.5 * (s0 + s1)
        if not clear(mid):  # pragma: no cover - a shapely fault
            raise InputError("outline", f"edge {i}'s usable part to clear the outline by the radius",
                             f"an overlap at fraction {mid:.4g}")
        s0, s1 = _refined(clear, s0, mid), _refined(clear, s1, mid)
        out.append(EdgeContact(i, a.copy(), b.copy(), (float(s0), float(s1)), n, half,
                               float((s1 - s0) * length * c * c)))
    return out


def _refined(clear: Callable[[float], bool], end: float, inner: float, steps: int = 60) -> float:
    """``end`` if the disc there clears the outline, else the clear fraction nearest to it found by
    bisection towards ``inner`` (clear): the grown outline's chords let the interval overshoot by
    up to a few micrometres, which the exact distance removes."""
    if clear(end):
        return end
    bad, good = end, inner
    for _ in range(steps):
        m = 0.5 * (bad + good)
        bad, good = (bad, m) if clear(m) else (m, good)
    return good


def _normal_angle(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    e = b - a
    return float(np.arctan2(-e[0], e[1]))


def vertex_contacts(outline: shapely.Polygon, radius: float, friction: float,
                    samples: int = 16) -> list[VertexContact]:
    """Every convex vertex with the range of contact normals (sampled at ``samples`` angles between
    the adjacent edges' normals, the longest clear run kept) at which the object clears the outline."""
    ring = ring_of(outline)
    n = len(ring)
    half = float(np.arctan(friction))
    out = []
    for i in range(n):
        prev, v, nxt = ring[i - 1], ring[i], ring[(i + 1) % n]
        d1, d2 = v - prev, nxt - v
        if d1[0] * d2[1] - d1[1] * d2[0] <= 0.0:  # reflex or straight: not a point pusher
            continue
        lo = _normal_angle(prev, v)
        hi = lo + float(np.mod(_normal_angle(v, nxt) - lo, 2 * np.pi))
        angles = np.linspace(lo, hi, samples)
        centres = v + radius * np.column_stack([np.cos(angles), np.sin(angles)])
        dist = shapely.distance(outline, shapely.points(centres))
        ok = dist >= radius - CHECK_TOL
        if not ok.any():
            continue
        k0, k1 = _longest_run(ok)
        out.append(VertexContact(i, v.copy(), (float(angles[k0]), float(angles[k1 - 1])), half))
    return out


def _longest_run(flags: NDArray[np.bool_]) -> tuple[int, int]:
    """``(k0, k1)``: the longest run ``flags[k0:k1]`` of True (the first of equal ones)."""
    best, start = (0, 0), None
    for k, good in enumerate([*flags.tolist(), False]):
        if good and start is None:
            start = k
        elif not good and start is not None:
            if k - start > best[1] - best[0]:
                best = (start, k)
            start = None
    return best
