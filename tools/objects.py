"""The pushed object (a disc by default, a convex polygon where cheap) and obstacle shapes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
import shapely.affinity
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.decompose import is_convex
from tooltransfer.validation import check_array, check_positive

#: Radius of the paper's object [m] (Table II: 17.5 mm).
OBJECT_RADIUS = 0.0175


@dataclass(frozen=True)
class DiscObject:
    """A round object (puck) of radius ``radius`` [m]; Table II's object by default."""

    radius: float = OBJECT_RADIUS

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", check_positive(self.radius, "radius"))

    def support(self, direction: ArrayLike) -> NDArray[np.float64]:
        """Offset (2,) [m] from the centre to the boundary point farthest along ``direction``."""
        d = np.asarray(direction, dtype=np.float64)
        return self.radius * d / np.hypot(*d)

    def at(self, centre: ArrayLike) -> Disc:
        """The object placed with its centre at ``centre`` (2,) [m]."""
        return Disc(check_array(centre, "centre", shape=(2,)), self.radius)


@dataclass(frozen=True)
class PolygonObject:
    """A convex polygonal object; ``outline`` is in the object frame (origin = reference point) [m].

    The object does not rotate in this model (translation only), so its frame is parallel to the
    world's.
    """

    outline: shapely.Polygon

    def __post_init__(self) -> None:
        poly = self.outline
        if not isinstance(poly, shapely.Polygon) or not poly.is_valid or poly.area <= 0:
            raise InputError("outline", "a valid polygon with positive area", repr(poly)[:60])
        if not is_convex(poly):
            raise InputError("outline", "a convex polygon", "a non-convex outline")

    def support(self, direction: ArrayLike) -> NDArray[np.float64]:
        """Vertex (2,) [m] farthest along ``direction`` (object frame)."""
        c = np.asarray(self.outline.exterior.coords, dtype=np.float64)[:-1]
        return c[int(np.argmax(c @ np.asarray(direction, dtype=np.float64)))]

    def at(self, centre: ArrayLike) -> shapely.Polygon:
        """The object placed with its reference point at ``centre`` (2,) [m]."""
        c = check_array(centre, "centre", shape=(2,))
        return shapely.affinity.translate(self.outline, float(c[0]), float(c[1]))


@dataclass(frozen=True)
class Disc:
    """A disc in the world: ``centre`` (2,) [m] and ``radius`` [m] (placed object or obstacle)."""

    centre: NDArray[np.float64]
    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "centre", check_array(self.centre, "centre", shape=(2,)))
        object.__setattr__(self, "radius", check_positive(self.radius, "radius"))

    def polygon(self, quad_segs: int = 64) -> shapely.Polygon:
        """A polygon inscribed in the disc (for drawing; exact maths uses centre and radius)."""
        return shapely.Point(self.centre).buffer(self.radius, quad_segs=quad_segs)


Obstacle = Disc | shapely.Polygon
ObjectModel = DiscObject | PolygonObject
