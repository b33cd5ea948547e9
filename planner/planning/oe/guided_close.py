"""The steps of the guided search's closest attempt: a way that passes within a millimetre of an obstacle,
the contact kept to a millimetre of its face.

The ladder's other attempts (:mod:`tooltransfer.planner.planning.oe.guided_rungs`) check a face's hold where a
step starts, keep the tool a millimetre or more from the obstacles at their nodes, and step in three
directions of the face's cone. Where all of them fail, a way may still pass nearer an obstacle than that room
(on the verdict benchmark, the tool clears the obstacle only within half a millimetre on the way to
``verd200-00120``'s target). This attempt (:data:`~.guided_rungs.CLOSE`, run by
:func:`~tooltransfer.planner.planning.oe.guided.guided_path` with ``close``) keeps :data:`CLOSE_ROOM` at its
nodes, and makes up for the lesser room with rules nearer the fit's:

- a step ends where its own face (or window) still holds the puck: a step into a place its face cannot hold
  leaves the fit a run it cannot follow (the tool outline over an obstacle at the step's end);
- where the whole step does not, or rolls the contact off its window, its half and then its quarter are tried
  (:data:`CLOSE_LEVELS`), each on cells that much finer;
- a step rolls the contact at most ``width`` per :data:`~.contacts.MIN_PIECE` of travel (the push's
  realisation, :func:`~.contacts.realise_span`, refuses a contact that carries the puck less far);
- every re-contact starts a new run, fitted on its own from rest to rest (:func:`~.piecewise.fit_runs`);
- :data:`CLOSE_DIRECTIONS` directions across the face's cone.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.contacts import MIN_PIECE
from tooltransfer.planner.planning.oe.guided_moves import _Contact, _FaceMoves, _roll, _rolled, _stepped
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.setting import Setting

#: Room [m] the closest attempt keeps between the tool outline and the obstacles at its nodes: the hard
#: check's ``TOOL_MARGIN`` (0.25 mm) and 0.15 mm for the fit, which follows the path within a few hundredths
#: of a millimetre but places the contact anywhere in its window.
CLOSE_ROOM = 4e-4
#: How many sizes of a step the closest attempt tries: the whole, then each half of the one before.
CLOSE_LEVELS = 3
#: Directions across a face's cone the closest attempt steps in (its edges, its middle and between).
CLOSE_DIRECTIONS = 5
#: Share of :data:`~.contacts.MIN_PIECE` the roll rate keeps below (the realised contact's roll is the fit's,
#: the search's an estimate at the window's middle).
ROLL_SHARE = 0.9


def close_angles(mid: float, half: float) -> NDArray[np.float64]:
    """The directions [rad] the closest attempt steps in: :data:`CLOSE_DIRECTIONS` evenly across
    ``mid +- half``."""
    return mid + half * np.linspace(-1.0, 1.0, CLOSE_DIRECTIONS)


def close_step(setting: Setting, options: QPOptions, fm: _FaceMoves, came: str | None, touch: _Contact,
               p: NDArray[np.float64], ang: float, half: float, step: float,
               free: Callable[[NDArray[np.float64]], bool],
               holds: Callable[[NDArray[np.float64], str], bool]) -> tuple[NDArray[np.float64], _Contact, int] | None:
    """A step of ``fm`` from ``p`` (2,) [m] toward ``ang`` [rad] under the closest attempt's rules (module
    docstring): ``(end, contact after it, level)``, the step ``step / 2**level`` [m] long, or None where no size
    is one. ``options``: the search's, with ``max_contacts`` 1 (each re-contact a run of its own, module
    docstring); ``came``, ``touch``: the node's face key and contact; ``half`` [rad]: the cone's half-width the
    search uses; ``free``: whether the puck's centre may be at a point; ``holds``: whether a face key holds
    the puck at a point."""
    for level in range(CLOSE_LEVELS):
        size = step / 2 ** level
        q = _stepped(fm, p, ang, half, size)
        if q is None:
            return None
        ds = _roll(fm, p, q, setting.mechanics.rolling, setting.radius)
        if not free(q) or abs(ds) > ROLL_SHARE * fm.width * size / MIN_PIECE:
            continue
        after = _rolled(setting, options, fm, came, touch, p, q, True, ds)
        if after is None or not holds(q, fm.key):
            continue
        return q, after, level
    return None
