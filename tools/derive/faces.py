"""Planner faces derived from a tool outline: :func:`derive_faces` (docs/design.md section 13).

Every edge contact of :mod:`tooltransfer.tools.derive.contacts` that the Omni can push with becomes a
:class:`~tooltransfer.tools.model.Face` named ``edge_<i>`` (``i`` the edge's index in the outline's
counter-clockwise ring): its segment is the whole edge, its ``contact_range`` the usable part, its
``push_angle`` the outward normal and its ``theta_b`` the friction cone's half-angle ``atan(mu)``.
A usable part longer than :data:`CONTACT_WINDOW` gives the face the window of that length nearest
the tool centre point (the edge contact keeps the whole part): the planner lets a contact use
``oe.contact_span`` (12 mm by default) about the middle of a face's range and plans the reach there,
and of a long edge the derivation offers the stretch nearest the tool centre point, next to where
the Omni holds the tool (as the paper places tool 1's left face, just below its head).

The planner intersects a face's ``push_angle +- theta_b`` with the friction cone of the task's
mechanics (:func:`tooltransfer.planner.planning.oe.face_frame.admissible_cone`), so a derived face
allows every direction the mechanics allow; an operator's narrower preference stays what a tool
file's hand-written faces say.

At most :data:`MAX_DERIVED_FACES` faces are kept (the longest usable parts): the push-sequence
search grows as ``faces ** max_pushes`` and a task is refused beyond
:data:`tooltransfer.problems.task.MAX_SEARCH_STEPS` (8 faces fit with the default ``oe.max_pushes``
4 and ``oe.segments`` 10).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import shapely

from tooltransfer.errors import InputError
from tooltransfer.tools.derive.contacts import EdgeContact, VertexContact, edge_contacts, vertex_contacts
from tooltransfer.tools.derive.defaults import (  # the defaults, under their names here too
    CONTACT_WINDOW,
    DEFAULT_C,
    DEFAULT_FRICTION,
    MAX_DERIVED_FACES,
    MIN_LENGTH,
)
from tooltransfer.tools.model import Face
from tooltransfer.tools.objects import OBJECT_RADIUS
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.omni.reach import ReachSector, reach_sector


@dataclass(frozen=True)
class Derivation:
    """What :func:`derive_faces` found on one outline.

    Attributes:
        outline: the outline, counter-clockwise [m].
        radius: the object's radius [m]; friction: tool-object ``mu``; c: limit-surface ratio.
        edges: every usable edge contact, in ring order (including those the Omni cannot use).
        vertices: every convex vertex usable as a point pusher.
        faces: the planner faces (at most ``max_faces``, ring order).
    """

    outline: shapely.Polygon
    radius: float
    friction: float
    c: float
    edges: tuple[EdgeContact, ...]
    vertices: tuple[VertexContact, ...]
    faces: tuple[Face, ...]

    def edge(self, name: str) -> EdgeContact:
        """The edge contact called ``name`` (``edge_<i>``)."""
        for e in self.edges:
            if e.name == name:
                return e
        raise KeyError(name)


def _positive(value: float, field: str, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating) or not np.isfinite(value) \
            or not 0.0 < value <= hi:
        raise InputError(field, f"a number in (0, {hi:g}]", repr(value))
    return float(value)


def _on_platform(e: EdgeContact, radius: float, sec: ReachSector) -> EdgeContact:
    """``e`` with its world push directions across the reach sector ``sec``, and whether the object's
    centre lies beyond the arm's axis at both ends of the usable part (``u_in + c_y > 0``)."""
    ends = [e.start + s * (e.end - e.start) + radius * e.normal for s in e.contact_range]
    ok = all(sec.u_range[0] + float(c[1]) > 0.0 for c in ends)
    waist = (sec.base_yaw + sec.q1_range[0], sec.base_yaw + sec.q1_range[1])
    lo = waist[0] - np.pi / 2 + e.normal_angle - e.friction_half
    hi = waist[1] - np.pi / 2 + e.normal_angle + e.friction_half
    return replace(e, world_directions=(float(lo), float(hi)), on_platform=ok)


def _window(e: EdgeContact, window: float) -> tuple[float, float]:
    """The fractions of ``e``'s usable part, or of its stretch of length ``window`` [m] nearest the
    tool centre point (the origin) when the part is longer."""
    s0, s1 = e.contact_range
    half = 0.5 * window / e.length
    if s1 - s0 <= 2 * half:
        return s0, s1
    foot = float(-(e.start @ (e.end - e.start)) / (e.length * e.length))  # origin's projection on the edge
    mid = min(max(foot, s0 + half), s1 - half)
    return float(mid - half), float(mid + half)


def derive_faces(
    outline: shapely.Polygon,
    object_radius: float = OBJECT_RADIUS,
    friction: float = DEFAULT_FRICTION,
    *,
    c: float = DEFAULT_C,
    min_length: float = MIN_LENGTH,
    max_faces: int = MAX_DERIVED_FACES,
    window: float = CONTACT_WINDOW,
    platform: OmniPlatform | None = None,
) -> Derivation:
    """Every usable contact of ``outline`` for a disc of ``object_radius`` [m] and the faces to plan with.

    Args:
        outline: a simple polygon in the tool frame [m], either orientation.
        object_radius: the object's radius [m].
        friction: tool-object Coulomb friction ``mu`` (the cone half-angle is ``atan(mu)``).
        c: the object's limit-surface ratio (sideways travel per contact, ``l c^2``).
        min_length: shortest usable part [m] of an edge that makes a face.
        max_faces: most faces kept (the longest usable parts).
        window: longest contact range of a face [m] (see the module docstring).
        platform: the Omni carrying the tool; with it, faces the Omni cannot push with are dropped
            and each edge contact carries its world push directions.

    Raises:
        InputError: a bad number, an invalid outline, or an outline with no usable edge.
    """
    if not isinstance(outline, shapely.Polygon) or outline.is_empty or not outline.is_valid or outline.interiors:
        raise InputError("outline", "a simple polygon without holes", repr(outline)[:100])
    radius = _positive(object_radius, "object_radius", 1.0)
    mu = _positive(friction, "friction", 10.0)
    c = _positive(c, "c", 2.0)
    min_length = _positive(min_length, "min_length", 1.0)
    window = _positive(window, "window", 1.0)
    if isinstance(max_faces, bool) or not isinstance(max_faces, int) or max_faces < 1:
        raise InputError("max_faces", "a positive integer", repr(max_faces))
    ccw = shapely.geometry.polygon.orient(outline, sign=1.0)
    edges = edge_contacts(ccw, radius, mu, c, min_length)
    if platform is not None:
        sec = reach_sector(platform)
        edges = [_on_platform(e, radius, sec) for e in edges]
    usable = [e for e in edges if e.on_platform]
    if not usable:
        raise InputError("outline", f"an edge of at least {min_length * 1e3:g} mm the object of radius "
                         f"{radius * 1e3:g} mm can touch (and the Omni can push with)", "none")
    keep = sorted(sorted(usable, key=lambda e: -e.usable_length)[:max_faces], key=lambda e: e.edge)
    faces = tuple(Face(e.name, e.start, e.end, e.normal_angle, e.friction_half, _window(e, window), e.normal)
                  for e in keep)
    return Derivation(ccw, radius, mu, c, tuple(edges), tuple(vertex_contacts(ccw, radius, mu)), faces)
