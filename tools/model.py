"""Tools as data: a planar outline in the tool frame plus named faces with push cones.

Tool frame: origin at the DH tool frame's origin (the paper's "tool centre point") projected on
the pushing plane; +y points along the arm away from the Omni base, +x to its right, so with the
tool's heading at 0 the tool frame is parallel to the world frame (docs/design.md section 2). Lengths in
metres, angles in radians measured from +x counter-clockwise.

A face is a straight piece of the outline. It carries the push direction ``push_angle`` (the
direction the object moves when pushed by this face, in the tool frame), the half-angle
``theta_b`` of the cone of directions it can push in (the yellow ranges of the paper's Fig. 5),
and the fractions ``contact_range = (s0, s1)`` of the segment where contact is allowed (0 at
``start``, 1 at ``end``). Every direction of the cone must have a positive component along the
face's outward normal (a face cannot pull), i.e. ``|push_angle - normal_angle| + theta_b < pi/2``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from itertools import pairwise

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.decompose import convex_decomposition
from tooltransfer.tools.errors import ToolSpecError, UnknownFaceError
from tooltransfer.tools.pose import wrap_angle

#: Distance [m] within which a face must lie on the outline.
ON_OUTLINE_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class Face:
    """A straight contact face of a tool (tool frame).

    Attributes:
        name: unique within the tool.
        start, end: shape (2,), segment end points [m].
        push_angle: direction the object is pushed in [rad].
        theta_b: cone half-angle [rad], in (0, pi/2).
        contact_range: fractions ``(s0, s1)`` of the segment usable for contact, 0 <= s0 <= s1 <= 1.
        normal: shape (2,), outward unit normal (filled in by :class:`Tool`).
    """

    name: str
    start: NDArray[np.float64]
    end: NDArray[np.float64]
    push_angle: float
    theta_b: float
    contact_range: tuple[float, float] = (0.0, 1.0)
    normal: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2), compare=False)

    @property
    def length(self) -> float:
        """Segment length [m]."""
        return float(np.hypot(*(self.end - self.start)))

    @property
    def normal_angle(self) -> float:
        """Angle of the outward normal [rad]."""
        return float(np.arctan2(self.normal[1], self.normal[0]))

    @property
    def push_direction(self) -> NDArray[np.float64]:
        """Unit push direction (2,) in the tool frame."""
        return np.array([np.cos(self.push_angle), np.sin(self.push_angle)])

    def point(self, s: float) -> NDArray[np.float64]:
        """Point (2,) [m] at fraction ``s`` along the segment (0 at ``start``)."""
        return self.start + s * (self.end - self.start)

    def contact_segment(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """End points (2,), (2,) [m] of the usable contact part of the face."""
        return self.point(self.contact_range[0]), self.point(self.contact_range[1])

    def in_cone(self, angle: float, atol: float = 1e-12) -> bool:
        """Whether the tool-frame direction ``angle`` [rad] is inside this face's push cone."""
        return abs(wrap_angle(angle - self.push_angle)) <= self.theta_b + atol


def _edge_normal(
    ring: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
) -> NDArray[np.float64] | None:
    """Outward normal of the CCW ring's edge that contains segment ``ab``, or None."""
    for p, q in pairwise(ring):
        e = q - p
        n2 = float(e @ e)
        if n2 == 0.0:
            continue
        ok = True
        for x in (a, b):
            t = float((x - p) @ e) / n2
            r = x - p
            dist = abs(float(e[0] * r[1] - e[1] * r[0])) / np.sqrt(n2)
            if (
                dist > ON_OUTLINE_TOL
                or t < -ON_OUTLINE_TOL / np.sqrt(n2)
                or t > 1 + ON_OUTLINE_TOL / np.sqrt(n2)
            ):
                ok = False
                break
        if ok:
            return np.array([e[1], -e[0]]) / np.sqrt(n2)
    return None


@dataclass(frozen=True, eq=False)
class Tool:
    """A pushing tool: outline, faces and the DH tool length.

    Attributes:
        name: library name of the tool.
        outline: simple polygon in the tool frame [m] (counter-clockwise after construction).
        faces: the contact faces, at least one.
        a_t: distance a_t [m] from the Omni's end to the tool centre point (Table I tool row).
        description: one line, for listings and figures.
        notes: where each number comes from (paper table, figure, or this project's choice).

    Raises:
        ToolSpecError: naming the tool and the field, when any of the above is invalid.
    """

    name: str
    outline: shapely.Polygon
    faces: tuple[Face, ...]
    a_t: float
    description: str = ""
    notes: str = ""

    def __post_init__(self) -> None:
        name = self.name if isinstance(self.name, str) and self.name else "?"
        if name == "?":
            raise ToolSpecError(name, "name", "a non-empty string is required")
        if not isinstance(self.a_t, int | float) or not np.isfinite(self.a_t) or self.a_t <= 0:
            raise ToolSpecError(name, "a_t", f"a positive length [m] is required, got {self.a_t!r}")
        object.__setattr__(self, "a_t", float(self.a_t))
        object.__setattr__(self, "outline", self._checked_outline(name))
        ring = np.asarray(self.outline.exterior.coords, dtype=np.float64)
        faces = tuple(self.faces)
        if not faces:
            raise ToolSpecError(name, "faces", "at least one face is required")
        seen: set[str] = set()
        checked = []
        for i, f in enumerate(faces):
            checked.append(self._checked_face(name, i, f, ring, seen))
        object.__setattr__(self, "faces", tuple(checked))

    def _checked_outline(self, name: str) -> shapely.Polygon:
        poly = self.outline
        if not isinstance(poly, shapely.Polygon) or poly.is_empty:
            raise ToolSpecError(name, "outline", "a polygon is required")
        coords = np.asarray(poly.exterior.coords, dtype=np.float64)
        if len(coords) < 4 or not np.all(np.isfinite(coords)):
            raise ToolSpecError(name, "outline", "at least 3 finite vertices are required")
        if poly.interiors:
            raise ToolSpecError(name, "outline", "holes are not supported")
        if not poly.is_valid:
            raise ToolSpecError(
                name, "outline", f"not a simple polygon ({shapely.is_valid_reason(poly)})"
            )
        if poly.area <= 0.0:
            raise ToolSpecError(name, "outline", "the area must be positive")
        return shapely.geometry.polygon.orient(poly, sign=1.0)

    def _checked_face(
        self, name: str, i: int, f: Face, ring: NDArray[np.float64], seen: set[str]
    ) -> Face:
        where = f"faces[{i}]"
        if not isinstance(f, Face):
            raise ToolSpecError(name, where, "a Face is required")
        if not isinstance(f.name, str) or not f.name:
            raise ToolSpecError(name, f"{where}.name", "a non-empty string is required")
        if f.name in seen:
            raise ToolSpecError(name, f"{where}.name", f"duplicate face name {f.name!r}")
        seen.add(f.name)
        try:
            a = np.asarray(f.start, dtype=np.float64).reshape(2)
            b = np.asarray(f.end, dtype=np.float64).reshape(2)
        except (TypeError, ValueError) as exc:
            raise ToolSpecError(name, f"{where}.segment", "two points [x, y] are required") from exc
        if (
            not (np.all(np.isfinite(a)) and np.all(np.isfinite(b)))
            or np.hypot(*(b - a)) <= ON_OUTLINE_TOL
        ):
            raise ToolSpecError(name, f"{where}.segment", "two distinct finite points are required")
        normal = _edge_normal(ring, a, b)
        if normal is None:
            raise ToolSpecError(
                name,
                f"{where}.segment",
                f"face {f.name!r} does not lie on one straight edge of the outline "
                f"(tolerance {ON_OUTLINE_TOL} m)",
            )
        for attr in ("push_angle", "theta_b"):
            v = getattr(f, attr)
            if not isinstance(v, int | float) or not np.isfinite(v):
                raise ToolSpecError(
                    name, f"{where}.{attr}", f"a finite angle [rad] is required, got {v!r}"
                )
        if not 0.0 < f.theta_b < np.pi / 2:
            raise ToolSpecError(
                name, f"{where}.theta_b", f"must be in (0, pi/2) rad, got {f.theta_b!r}"
            )
        off = abs(wrap_angle(f.push_angle - np.arctan2(normal[1], normal[0])))
        if off + f.theta_b >= np.pi / 2:
            raise ToolSpecError(
                name,
                f"{where}.push_angle",
                f"the cone push_angle +- theta_b must stay within pi/2 of the outward normal "
                f"(offset {off:.4g} + theta_b {f.theta_b:.4g} >= pi/2)",
            )
        try:
            s0, s1 = (float(v) for v in f.contact_range)
        except (TypeError, ValueError) as exc:
            raise ToolSpecError(
                name, f"{where}.contact_range", "two fractions [s0, s1] are required"
            ) from exc
        if not 0.0 <= s0 <= s1 <= 1.0:
            raise ToolSpecError(
                name, f"{where}.contact_range", f"need 0 <= s0 <= s1 <= 1, got {[s0, s1]}"
            )
        return Face(f.name, a, b, float(f.push_angle), float(f.theta_b), (s0, s1), normal)

    def face(self, name: str) -> Face:
        """The face called ``name``; raises :class:`UnknownFaceError` listing the faces."""
        for f in self.faces:
            if f.name == name:
                return f
        raise UnknownFaceError(self.name, name, [f.name for f in self.faces])

    @property
    def face_names(self) -> tuple[str, ...]:
        """Names of the faces, in file order."""
        return tuple(f.name for f in self.faces)

    @cached_property
    def convex_pieces(self) -> tuple[shapely.Polygon, ...]:
        """Convex pieces (tool frame) whose union is the outline, checked exactly."""
        try:
            return convex_decomposition(self.outline)
        except InputError as exc:  # pragma: no cover - the outline is validated above
            raise ToolSpecError(self.name, "outline", str(exc)) from exc

    @property
    def radius(self) -> float:
        """Largest distance [m] of an outline vertex from the tool frame origin."""
        c = np.asarray(self.outline.exterior.coords)
        return float(np.max(np.hypot(c[:, 0], c[:, 1])))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Tool):
            return NotImplemented
        same_faces = len(self.faces) == len(other.faces) and all(
            a.name == b.name
            and np.allclose(a.start, b.start, rtol=0, atol=1e-15)
            and np.allclose(a.end, b.end, rtol=0, atol=1e-15)
            and a.push_angle == b.push_angle
            and a.theta_b == b.theta_b
            and a.contact_range == b.contact_range
            for a, b in zip(self.faces, other.faces, strict=False)
        )
        return (
            self.name == other.name
            and self.a_t == other.a_t
            and same_faces
            and self.outline.equals_exact(other.outline, 0.0)
            and self.description == other.description
            and self.notes == other.notes
        )

    __hash__ = None  # type: ignore[assignment]
