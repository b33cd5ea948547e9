"""What one face of the tool can do where the guided search holds the object: its moves.

For each face (or each contact window of a face, :func:`contact_windows`) the frames of its heading
cone and of the ends of its usable contact range (the Omni must hold the tool at both), the direction
its admissible pushes point in with the object at a position, a step kept inside that cone at both
of its ends, and how far a step rolls the contact along the face (the inverse push model's
``1/c^2`` rolling, :mod:`tooltransfer.tools.pushing.inverse`), with the re-contacts that keeps the
contact on the face. The search itself is :mod:`tooltransfer.planner.planning.oe.guided`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.contacts import usable_range
from tooltransfer.planner.planning.oe.face_frame import FaceFrame, admissible_cone
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.tools.model import Face, Tool
from tooltransfer.tools.pushing.inverse import FaceGeometry


@dataclass(frozen=True)
class _FaceMoves:
    """What the ``qp`` fit demands of one face (:class:`~tooltransfer.planner.planning.oe.sequence_fit.SequenceFit`):
    the frame of its heading cone (contact at the middle of the face) and the frames at the ends of the
    contact's usable range, from each of which the Omni must reach the object, with the farthest the
    tool outline reaches [m] from the object's centre there (a body farther from an obstacle cannot
    touch it)."""

    name: str
    cone: FaceFrame
    ends: tuple[FaceFrame, ...]
    spans: tuple[float, ...]
    direction: tuple[float, float]
    sigma: float
    width: float
    key: str
    window: tuple[float, float] | None


#: Most contact windows per face (:func:`contact_windows`; odd, so that the face's middle is one).
MAX_WINDOWS = 5


def contact_windows(tool: Tool, face: str, options: QPOptions, most: int = MAX_WINDOWS) -> list[tuple[float, float]]:
    """Stretches ``(lo, hi)`` [m] of ``options.contact_span`` along ``face``'s contact range less the
    contact margin, evenly placed from one end of it to the other (an odd number, at most ``most``
    (odd), the middle one :func:`usable_range`'s): where the Omni holds the tool only with the contact
    toward one end of a face, a run of it keeps its contact there. A face no longer than a span has the
    one window of :func:`usable_range`."""
    g = FaceGeometry.of(tool, face)
    lo, hi = g.lo + options.contact_margin, g.hi - options.contact_margin
    w = options.contact_span
    if hi - lo <= w:
        return [usable_range(tool, face, options)]
    n = min(most, math.ceil((hi - lo) / w))
    n += 1 - n % 2
    return [(float(c - 0.5 * w), float(c + 0.5 * w)) for c in np.linspace(lo + 0.5 * w, hi - 0.5 * w, n)]


def face_cone(setting: Setting, face: Face, share: float) -> tuple[float, float] | None:
    """``face``'s admissible cone ``(lo, hi)`` [rad] in the tool's frame at ``share`` of the friction cone's
    half-angle (:func:`~.face_frame.admissible_cone`), or None where it cannot push at that share."""
    lo, hi = admissible_cone(face.normal_angle, face.push_angle, face.theta_b,
                             share * setting.mechanics.friction_angle)
    return (lo, hi) if hi > lo else None


def _face_moves(setting: Setting, options: QPOptions, windows: bool = False,
                most: int = MAX_WINDOWS) -> list[_FaceMoves]:
    """One :class:`_FaceMoves` per face that can push under ``options`` (the plan's narrowed cone, its
    contact margin and span), or one per face and contact window (:func:`contact_windows`, at most ``most``
    per face)."""
    out = []
    cone_share = options.friction_cone_fraction
    for f in setting.tool.faces:
        if face_cone(setting, f, cone_share) is None:
            continue
        g = FaceGeometry.of(setting.tool, f.name)
        ranges = (contact_windows(setting.tool, f.name, options, most) if windows
                  else [usable_range(setting.tool, f.name, options)])
        for i, (a, b) in enumerate(ranges):
            one = len(ranges) == 1
            mid = None if one else 0.5 * (a + b) / f.length
            cone = FaceFrame.build(setting, f.name, s=mid, friction_cone_fraction=cone_share)
            ends = tuple(FaceFrame.build(setting, f.name, s=v / f.length, friction_cone_fraction=cone_share)
                         for v in sorted({a, b}))
            outline = np.asarray(setting.tool.outline.exterior.coords)
            spans = tuple(float(np.hypot(*(outline - e.centre_in_tool).T).max()) for e in ends)
            out.append(_FaceMoves(f.name, cone, ends, spans, (float(g.direction[0]), float(g.direction[1])),
                                  g.sigma, b - a, f.name if one else f"{f.name}@{i}", None if one else (a, b)))
    return out


def _heading(frame: FaceFrame, p: NDArray[np.float64]) -> float | None:
    """The tool's yaw [rad] with ``frame``'s contact holding the object at ``p`` (2,) [m]
    (:meth:`FaceFrame.heading` for one point), or None where the Omni holds it nowhere (outside its
    reach or waist range, with :data:`REACH_SLACK` to spare: the fit's reach rows are an inner
    approximation within 2e-4 m)."""
    dx, dy = float(p[0] - frame.base[0]), float(p[1] - frame.base[1])
    r2 = dx * dx + dy * dy
    if r2 <= frame.offset ** 2:
        return None
    u = math.sqrt(r2 - frame.offset ** 2)
    a = math.atan2(dy, dx) - math.atan2(frame.offset, u)
    if not (frame.reach[0] + REACH_SLACK <= u <= frame.reach[1] - REACH_SLACK
            and frame.waist[0] + REACH_SLACK / u <= a <= frame.waist[1] - REACH_SLACK / u):
        return None
    return a - math.pi / 2


#: Room [m] the search keeps inside the Omni's reach and, but in its attempts on windows where needed
#: (:data:`~.guided_rungs.LAST_ROOM`), between the tool outline and the obstacles.
REACH_SLACK = 5e-4

#: Share of a cone's half-width a step turned back inside it aims at (:func:`_stepped`).
EDGE_INSIDE = 0.95

def _pointing(fm: _FaceMoves, p: NDArray[np.float64]) -> float:
    """The middle [rad] of ``fm``'s admissible directions in the world with the object at ``p``."""
    yaw = _heading(fm.cone, p)
    if yaw is None:  # the middle of the range is between its ends: held wherever they are
        yaw = float(fm.cone.heading(p[None])[0])
    return yaw + fm.cone.push_angle


def _roll(fm: _FaceMoves, p: NDArray[np.float64], q: NDArray[np.float64], rolling: float, radius: float) -> float:
    """How far [m] the contact rolls along ``fm``'s face while it pushes the object from ``p`` to ``q``
    (2,) [m] (:mod:`tooltransfer.tools.pushing.inverse`: ``ds = -rolling (d . e_w) - sigma R dpsi`` with
    ``rolling = 1 / c^2``), the heading taken with the contact at the face's middle."""
    a, b = _yaw(fm, p), _yaw(fm, q)
    turn = math.remainder(b - a, 2 * math.pi)
    mid = a + 0.5 * turn
    ex, ey = fm.direction
    wx, wy = math.cos(mid) * ex - math.sin(mid) * ey, math.sin(mid) * ex + math.cos(mid) * ey
    return -rolling * (float(q[0] - p[0]) * wx + float(q[1] - p[1]) * wy) - fm.sigma * radius * turn


def _yaw(fm: _FaceMoves, p: NDArray[np.float64]) -> float:
    """The tool's yaw [rad] with ``fm``'s middle contact holding the object at ``p`` (2,) [m]."""
    yaw = _heading(fm.cone, p)
    return float(fm.cone.heading(p[None])[0]) if yaw is None else yaw


@dataclass(frozen=True)
class _Contact:
    """The contact of the run a search node is in: how many contacts of its face the run has used, the
    excursion ``(lo, now, hi)`` [m] of the present one's travel along the face since it began, and how
    many runs of the face came before it without a change of face (``run``: the object stopped and the
    face touched it again, each run one fit of at most ``oe.max_contacts`` contacts)."""

    count: int = 1
    lo: float = 0.0
    now: float = 0.0
    hi: float = 0.0
    run: int = 0

    def after(self, ds: float, width: float) -> _Contact | None:
        """This contact after rolling ``ds`` [m]; a new contact of the face (a re-contact) where the
        excursion would outgrow ``width`` [m]; None where one step alone outgrows it."""
        now = self.now + ds
        if max(self.hi, now) - min(self.lo, now) <= width:
            return _Contact(self.count, min(self.lo, now), now, max(self.hi, now), self.run)
        if abs(ds) > width:
            return None
        return _Contact(self.count + 1, min(0.0, ds), ds, max(0.0, ds), self.run)


def _stepped(fm: _FaceMoves, p: NDArray[np.float64], ang: float, half: float,
             step: float) -> NDArray[np.float64] | None:
    """Where a step of ``step`` [m] of ``fm`` in direction ``ang`` [rad] from ``p`` ends, its direction kept inside
    the face's cone at both ends of the step (the cone turns with the heading the Omni imposes, so a
    step along its edge at ``p`` may leave it at the step's end: it is turned back inside), or None
    where no direction near ``ang`` is inside both."""
    for _ in range(3):
        q = p + step * np.array([math.cos(ang), math.sin(ang)])
        off = math.remainder(ang - _pointing(fm, q), 2 * math.pi)
        if abs(off) <= half:
            return q
        # turned back to just inside the edge: the cone at the new end turns a little further with
        # it, so aiming at the edge itself would fall outside again, however many times repeated
        ang -= off - math.copysign(EDGE_INSIDE * half, off)
    return None


def _rolled(setting: Setting, options: QPOptions, fm: _FaceMoves, came: str | None, touch: _Contact,
            p: NDArray[np.float64], q: NDArray[np.float64], new_runs: bool = False,
            ds: float | None = None) -> _Contact | None:
    """The contact of ``fm`` after it pushes the object from ``p`` to ``q`` (2,) [m]: ``touch`` rolled on
    where the node's face ``came`` is ``fm``'s, a run's first contact where the face changes; where the
    run would need more than ``options.max_contacts`` contacts, a new run of the face (``new_runs``) or
    None; None where the step alone rolls the contact across more than the face's usable range. ``ds`` [m]:
    the step's roll (:func:`_roll`), where already known."""
    own = touch if came == fm.key else _Contact()
    ds = _roll(fm, p, q, setting.mechanics.rolling, setting.radius) if ds is None else ds
    after = own.after(ds, fm.width)
    if after is not None and after.count > options.max_contacts:
        return _Contact(1, min(0.0, ds), ds, max(0.0, ds), own.run + 1) if new_runs else None
    return after


def _step_of(setting: Setting, options: QPOptions, fm: _FaceMoves, came: str | None, touch: _Contact,
             p: NDArray[np.float64], ang: float, half: float, step: float, more: bool = False,
             ) -> tuple[NDArray[np.float64], _Contact] | None:
    """A step of ``fm`` from ``p`` toward ``ang`` [rad] (:func:`_stepped`) and its contact after it
    (:func:`_rolled`, its ``new_runs`` with ``more``): of ``step`` [m], or with ``more`` of half of it
    where the whole step rolls the contact across more than the face's usable range (a short face
    pushing sideways re-touches every millimetre or two); None where neither is a step of the face."""
    for size in (step, 0.5 * step) if more else (step,):
        q = _stepped(fm, p, ang, half, size)
        if q is None:
            return None
        after = _rolled(setting, options, fm, came, touch, p, q, more)
        if after is not None:
            return q, after
    return None
