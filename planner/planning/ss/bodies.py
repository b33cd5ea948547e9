"""Shapes the switching tool must keep clear of, as parameter blocks of the switch NLP.

A body is a disc (centre, radius) or a convex polygon (its vertices); a non-convex polygonal
obstacle becomes several bodies, one per convex piece. Lengths here are in millimetres, the NLP's
internal unit (:mod:`tooltransfer.planner.planning.ss.nlp`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.tools.decompose import convex_decomposition
from tooltransfer.tools.objects import Disc, Obstacle

#: The NLP's length unit, in metres (millimetres: constraint rows and variables of order 1-100).
UNIT = 1e-3


@dataclass(frozen=True)
class Body:
    """One convex body: ``kind`` ``"disc"`` (``data`` = centre x, y, radius [mm]) or ``"poly"``
    (``data`` = vertices (V, 2) [mm], flattened); ``family`` names it in reasons (``"object"``,
    ``"obstacle 2"``)."""

    kind: str
    data: NDArray[np.float64]
    family: str

    @property
    def signature(self) -> tuple[str, int]:
        """What the solver's structure depends on: the kind and the parameter count."""
        return (self.kind, int(self.data.size))

    def centre(self) -> NDArray[np.float64]:
        """A point inside (2,) [mm]."""
        if self.kind == "disc":
            return self.data[:2]
        return self.data.reshape(-1, 2).mean(axis=0)


def bodies_of(shape: Disc | shapely.Polygon, family: str) -> list[Body]:
    """The convex bodies of a placed shape (world, metres in; millimetres out)."""
    if isinstance(shape, Disc):
        return [Body("disc", np.array([*shape.centre, shape.radius]) / UNIT, family)]
    out = []
    for piece in convex_decomposition(shape):
        v = np.asarray(shapely.geometry.polygon.orient(piece).exterior.coords, dtype=np.float64)[:-1]
        out.append(Body("poly", v.ravel() / UNIT, family))
    return out


def all_bodies(obj: Disc | shapely.Polygon, obstacles: Sequence[Obstacle]) -> list[Body]:
    """The object's bodies, then each obstacle's (family ``"obstacle i"``)."""
    out = bodies_of(obj, "object")
    for i, o in enumerate(obstacles):
        out += bodies_of(o, f"obstacle {i}")
    return out
