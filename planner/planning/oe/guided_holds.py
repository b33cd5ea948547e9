"""Where the guided search may hold the puck: which faces push it there, and where its centre may be.

The rules :func:`~tooltransfer.planner.planning.oe.guided.guided_path` expands its lattice under, and
:func:`~tooltransfer.planner.planning.oe.guided.guide_field` builds its distance field from: each face (or
window of a face, :func:`~.guided_moves.contact_windows`) holds the puck where the Omni reaches its contact
at both ends of its range and the tool outline there keeps ``room`` from the obstacles; the puck's centre
keeps its radius and the safety margin from them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.guided_moves import (
    MAX_WINDOWS,
    REACH_SLACK,
    _face_moves,
    _FaceMoves,
    _heading,
    _pointing,
)
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.tools.objects import Disc

#: Share of a face's narrowed cone the search's steps use (the fit's cone rows are linearised).
CONE = 0.98

def _zones(setting: Setting, room: float = REACH_SLACK) -> list[Any]:
    """Where the tool outline may not come (the obstacles grown by ``room`` [m]) and where the object's
    centre may not be (grown by its radius and the margin), prepared; None without obstacles."""
    obstacles = [o.polygon() if isinstance(o, Disc) else o for o in setting.obstacles]
    zones = [shapely.union_all([shapely.buffer(o, d, quad_segs=32) for o in obstacles]) if obstacles else None
             for d in (room, setting.radius + max(setting.margin - 1e-5, 0.0) + 1e-4)]
    for z in zones:
        if z is not None:
            shapely.prepare(z)
    return zones


@dataclass(frozen=True, eq=False)
class _Holds:
    """Which of the search's ``faces`` hold the object where: each at both ends of its usable contact
    range (or window), the Omni reaching it there, the tool ``outline`` (M, 2) [m] clear of the
    ``body_zone`` (:func:`_zones`; None without obstacles)."""

    faces: list[_FaceMoves]
    outline: NDArray[np.float64]
    body_zone: Any

    def touches(self, fm: _FaceMoves, yaws: list[float], p: NDArray[np.float64], near: float) -> bool:
        """Whether the tool outline, holding ``fm``'s contact at each end at the yaws [rad] with the
        object at ``p``, meets the body zone (``near`` [m]: the zone's distance from ``p``)."""
        close = [(e, y) for e, y, reach in zip(fm.ends, yaws, fm.spans, strict=True) if reach >= near]
        if not close:
            return False
        rings = np.stack([(self.outline - e.centre_in_tool) @ np.array([[math.cos(y), math.sin(y)],
                                                                       [-math.sin(y), math.cos(y)]]) + p
                          for e, y in close])
        return bool(shapely.intersects(self.body_zone, shapely.polygons(rings)).any())

    def near(self, p: NDArray[np.float64]) -> float:
        """The body zone's distance [m] from ``p`` (2,) [m] (infinite without obstacles)."""
        return math.inf if self.body_zone is None else float(shapely.distance(self.body_zone, shapely.Point(p)))

    def holds(self, fm: _FaceMoves, p: NDArray[np.float64], near: float | None = None) -> bool:
        """Whether ``fm`` (one face or window) holds the object at ``p`` (2,) [m]: the Omni reaching its contact at
        both ends of its range, the tool outline there clear of the body zone (``near``: its distance from ``p``,
        :meth:`near`, where already known)."""
        yaws = [_heading(e, p) for e in fm.ends]
        if any(y is None for y in yaws):
            return False
        return not self.touches(fm, [y for y in yaws if y is not None], p, self.near(p) if near is None else near)

    def __call__(self, p: NDArray[np.float64], came: str | None = None, every: bool = False,
                 ) -> list[tuple[str, float, float]]:
        """``(face, direction, half)`` [rad] of the faces that can push the object at ``p``: the middle
        of their admissible directions in the world and the half-width the search uses of them. A
        window of a face held as a whole (``mixed``) is left out unless the node's face ``came`` is it
        or ``every`` (the target of a last step, which adds no node to the lattice)."""
        near = self.near(p)
        out = []
        whole: set[str] = set()  # the faces held as a whole here
        for fm in self.faces:
            if fm.window is not None and fm.name in whole and fm.key != came and not every:
                continue
            if not self.holds(fm, p, near):
                continue
            out.append((fm.key, _pointing(fm, p), CONE * fm.cone.theta_b))
            if fm.window is None:
                whole.add(fm.name)
        return out


def straight_to(way: float, here: list[tuple[str, float, float]], there: list[tuple[str, float, float]]
                ) -> list[str]:
    """The keys of the faces of ``here`` (held at a point, as :class:`_Holds` gives them) also held in
    ``there`` (at another point) whose cones at both hold direction ``way`` [rad]: the faces that push the
    puck straight from the one point to the other, in ``here``'s order."""
    at = {key: (m, h) for key, m, h in there}
    return [key for key, m, h in here if key in at and all(abs(math.remainder(way - mm, 2 * math.pi)) <= hh
                                                            for mm, hh in ((m, h), at[key]))]


def lattice_rules(setting: Setting, options: QPOptions, windows: bool = False, mixed: float | None = None,
                  room: float = REACH_SLACK, most: int = MAX_WINDOWS,
                  ) -> tuple[_Holds, Callable[[NDArray[np.float64]], bool], dict[str, _FaceMoves]]:
    """The search's rules under ``options`` (module docstring; ``windows``, ``mixed`` [m], ``room`` [m] and
    ``most`` (the most windows per face) as :func:`~tooltransfer.planner.planning.oe.guided.guided_path`
    takes them): which faces hold the puck where (:class:`_Holds`), whether its centre may be at a point (2,)
    [m], and the faces by key."""
    outline = np.asarray(setting.tool.outline.exterior.coords)
    body_zone, centre_zone = _zones(setting, room)
    faces = _face_moves(setting, options, windows, most)
    if mixed is not None:
        faces += [fm for fm in _face_moves(setting, options.model_copy(update={"contact_span": mixed}), True, most)
                  if fm.window is not None]

    def free(q: NDArray[np.float64]) -> bool:
        return centre_zone is None or not shapely.intersects_xy(centre_zone, float(q[0]), float(q[1]))

    return _Holds(faces, outline, body_zone), free, {fm.key: fm for fm in faces}
