"""Planar rigid poses of a tool on the table: ``(x, y, yaw)`` [m, m, rad] in the world frame, and the
package's one angle wrapping (:func:`wrap_angle`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import overload

import numpy as np
import shapely
import shapely.affinity
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError


@overload
def wrap_angle(angle: float) -> float: ...


@overload
def wrap_angle(angle: NDArray[np.float64]) -> NDArray[np.float64]: ...


def wrap_angle(angle: float | NDArray[np.float64]) -> float | NDArray[np.float64]:
    """Angles [rad] wrapped into ``[-pi, pi)``: ``(angle + pi) mod 2 pi - pi``, elementwise.

    A float (also a NumPy scalar) gives a float, an array an array of the same shape. Every wrap in
    the package goes through this expression, so the same angle wraps to the same bits everywhere
    (``arctan2(sin a, cos a)`` differs from it in the last bits and gives ``+pi`` at ``pi``). Not
    validated: a NaN or infinite angle gives NaN.
    """
    wrapped = (angle + np.pi) % (2.0 * np.pi) - np.pi
    return wrapped if isinstance(wrapped, np.ndarray) else float(wrapped)


def rotation(yaw: float) -> NDArray[np.float64]:
    """2-D rotation matrix (2, 2) by ``yaw`` [rad]."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s], [s, c]])


def placed_outlines(ring: ArrayLike, xy: ArrayLike, yaw: ArrayLike) -> shapely.GeometryCollection:
    """The tool outline ``ring`` (V, 2) [m, tool frame] placed at each pose ``xy`` (K, 2) [m], ``yaw``
    (K,) [rad], as one collection of K polygons (what a swept-clearance check measures distances to).

    The coordinates are bit for bit ``ring @ rotation(yaw_k).T + xy_k`` (the same rotation matrices and
    one batched product), built at once instead of one shapely polygon per pose: a switch check places
    the outline some hundred times, and the polygons' construction was most of its cost."""
    ring, xy = np.asarray(ring, dtype=np.float64), np.asarray(xy, dtype=np.float64)
    if len(xy) == 0:
        return shapely.GeometryCollection()
    turns = np.stack([rotation(float(a)) for a in np.asarray(yaw, dtype=np.float64)])
    placed = ring[None] @ turns.transpose(0, 2, 1) + xy[:, None, :]
    return shapely.GeometryCollection(list(shapely.polygons(placed)))


@dataclass(frozen=True)
class Pose2D:
    """Tool frame in the world: origin ``(x, y)`` [m] and heading ``yaw`` [rad]."""

    x: float
    y: float
    yaw: float

    def __post_init__(self) -> None:
        for name in ("x", "y", "yaw"):
            v = getattr(self, name)
            if (
                isinstance(v, bool)
                or not isinstance(v, int | float | np.floating)
                or not np.isfinite(v)
            ):
                raise InputError(name, "a finite real number", repr(v))
            object.__setattr__(self, name, float(v))

    @property
    def position(self) -> NDArray[np.float64]:
        """Origin (2,) [m]."""
        return np.array([self.x, self.y])

    def apply(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map tool-frame points (..., 2) [m] to the world."""
        p = np.asarray(points, dtype=np.float64)
        return p @ rotation(self.yaw).T + self.position

    def apply_inverse(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map world points (..., 2) [m] to the tool frame."""
        p = np.asarray(points, dtype=np.float64)
        return (p - self.position) @ rotation(self.yaw)

    def rotate(self, vectors: ArrayLike) -> NDArray[np.float64]:
        """Rotate tool-frame vectors (..., 2) into the world (no translation)."""
        return np.asarray(vectors, dtype=np.float64) @ rotation(self.yaw).T

    def place(self, geom: shapely.Geometry) -> shapely.Geometry:
        """A shapely geometry given in the tool frame, moved to this pose."""
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        return shapely.affinity.affine_transform(geom, [c, -s, s, c, self.x, self.y])

    def interpolate(self, other: Pose2D, t: float) -> Pose2D:
        """Linear interpolation of position and yaw (no wrapping) at ``t`` in [0, 1]."""
        return Pose2D(
            self.x + t * (other.x - self.x),
            self.y + t * (other.y - self.y),
            self.yaw + t * (other.yaw - self.yaw),
        )
