"""From a condensed object path and its face spans to pushes the mechanics deliver (both OE variants).

Each span (a face and the samples it pushes) gets its tool path from the inverse push model
(:func:`tooltransfer.tools.pushing.inverse.push_tool_path`): the contact sticks, rolls along the face as the
object moves sideways and the heading turns, and the tool poses follow. Where the contact starts
is a rule: its excursion over the push is centred in the face's usable range (the range shrunk by
the options' ``contact_margin``), which is the start that leaves the most room at both ends, unless
the tool's body then comes within ``CLEAR`` of an obstacle: then, among the starts that keep the
excursion on the face, the one that keeps the tool farthest from the obstacles. When
one contact cannot carry the span's sideways travel, the span is split into several contacts of the
same face: the longest stretch whose excursion fits, then a *re-contact* (the tool backs off,
shifts along the object and approaches again while the object rests, planned like a switch by
:mod:`tooltransfer.planner.planning.recontact`), and so on. A stretch shorter than ``MIN_PIECE`` of object travel means
the face cannot carry that motion at all: the pushes are refused with the reason.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.errors import ToolTransferError
from tooltransfer.planner.planning.oe.push_plan import Push
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.pose import placed_outlines
from tooltransfer.tools.pushing.inverse import FaceGeometry, FacePush, contact_path, push_tool_path

if TYPE_CHECKING:
    from tooltransfer.planner.planning.setting import Setting

#: Shortest object travel [m] one contact must carry before a re-contact.
MIN_PIECE = 0.001
#: Clearance [m] of the tool's body from the obstacles below which the contact's start is chosen
#: to keep the tool farther away (:func:`_clear_start`).
CLEAR = 0.003


class ContactLimits(Protocol):
    """Where on a face the contact may be: the OE variants' options carry these (:class:`QPOptions`,
    :class:`MappingOptions`, from the task's ``oe.contact_margin`` and ``oe.contact_span``)."""

    @property
    def contact_margin(self) -> float:
        """Distance [m] the contact keeps from the ends of a face's usable range."""

    @property
    def contact_span(self) -> float:
        """Longest stretch [m] of a face the contact may use, about its middle."""


class PushRefused(ToolTransferError):
    """A span cannot be pushed by its face under the mechanics (the reason says where and why)."""


def usable_range(tool: Tool, face: str, limits: ContactLimits) -> tuple[float, float]:
    """Arc lengths ``[lo, hi]`` [m] along ``face`` the contact may use: the face's contact range less
    the ``limits``' ``contact_margin`` at both ends, at most ``contact_span`` about its middle (a long
    face keeps the contact near its middle, where the planner's reach rows hold), or within the
    window the ``limits`` name for the face (``contact_windows``, where they have one)."""
    g = FaceGeometry.of(tool, face)
    lo, hi = g.lo + limits.contact_margin, g.hi - limits.contact_margin
    window = getattr(limits, "contact_windows", {}).get(face)
    if window is not None and max(lo, window[0]) <= min(hi, window[1]):
        return max(lo, window[0]), min(hi, window[1])
    mid = 0.5 * (g.lo + g.hi)
    if hi <= lo:  # a face shorter than twice the margin: its middle only
        return mid, mid
    half = 0.5 * limits.contact_span
    return max(lo, mid - half), min(hi, mid + half)


def _inverse(setting: Setting, face: str, x: NDArray[np.float64], s0: float) -> FacePush:
    return push_tool_path(setting.tool, face, x, setting.radius, setting.mechanics, s0, platform=setting.platform)


def _arc(setting: Setting, face: str, x: NDArray[np.float64], s0: float) -> NDArray[np.float64]:
    """``_inverse(...).s`` without the tool poses (the contact's arc lengths [m] only)."""
    return contact_path(setting.tool, face, x, setting.radius, setting.mechanics, s0, platform=setting.platform)


def _longest_fit(travel: NDArray[np.float64], width: float) -> int:
    """Largest ``j`` such that ``travel[:j + 1]`` spans at most ``width``."""
    lo_run = np.minimum.accumulate(travel)
    hi_run = np.maximum.accumulate(travel)
    fits = np.flatnonzero(hi_run - lo_run <= width + 1e-12)
    return int(fits[-1])


def _tool_clearance(tool: Tool, poses: NDArray[np.float64], shapes: list[shapely.Geometry]) -> float:
    """Least distance [m] of the tool outline at ``poses`` (K, 3) (every 10th and the last) from ``shapes``."""
    ring = np.asarray(tool.outline.exterior.coords)
    pick = np.unique(np.append(np.arange(0, len(poses), 10), len(poses) - 1))
    placed = placed_outlines(ring, poses[pick, :2], poses[pick, 2])
    return float(min(shapely.distance(placed, s) for s in shapes))


def _clear_start(setting: Setting, face: str, x: NDArray[np.float64],
                 fp: FacePush, s0: float, lo: float, hi: float) -> tuple[FacePush, float]:
    """The contact start ``s0`` [m] of a piece: the centred one while the tool keeps ``CLEAR`` from
    every obstacle, else, among starts that keep the excursion on ``[lo, hi]``, the one that keeps the
    tool farthest from them (a long face slides the tool along it by up to its length)."""
    tool = setting.tool
    shapes = [o.polygon() if isinstance(o, Disc) else o for o in setting.obstacles]
    best = (_tool_clearance(tool, fp.tool_pose, shapes), fp, s0)
    if best[0] >= CLEAR:
        return fp, s0
    travel = fp.s - s0
    first, last = lo - float(travel.min()), hi - float(travel.max())
    for s in np.linspace(first, last, 5) if last > first + 1e-6 else ():
        cand = _inverse(setting, face, x, float(s))
        c = _tool_clearance(tool, cand.tool_pose, shapes)
        if c > best[0]:
            best = (c, cand, float(s))
    return best[1], best[2]


def realise_span(setting: Setting, face: str, t: NDArray[np.float64], x: NDArray[np.float64],
                 idx: NDArray[np.intp], limits: ContactLimits, s_first: float | None = None) -> list[Push]:
    """Pushes (one, or several with re-contacts) realising samples ``idx`` of the object path ``x``
    (T, 2) [m] at times ``t`` (T,) [s] with ``face`` of ``setting``'s tool, the contact within
    ``limits`` (:func:`usable_range`). With ``s_first`` [m] (where the face already
    touches the object, e.g. in the closed loop), the first contact starts there as long as it stays
    on the face for at least :data:`MIN_PIECE` of travel (else the rule applies).

    Raises:
        PushRefused: a contact would have to change within less than :data:`MIN_PIECE` of travel.
    """
    lo, hi = usable_range(setting.tool, face, limits)
    width, mid = hi - lo, 0.5 * (lo + hi)
    framed = mid if face in (getattr(limits, "contact_windows", None) or {}) else float("nan")
    out: list[Push] = []
    a = 0
    while True:
        piece = idx[a:]
        if piece.size < 2:  # nothing left to push (a span of one sample)
            return out
        s0, part = mid, piece
        if s_first is not None and a == 0:
            fp = _inverse(setting, face, x[piece], float(s_first))
            inside = (fp.s >= lo - 1e-6) & (fp.s <= hi + 1e-6)
            j = int(np.argmin(inside)) - 1 if not inside.all() else piece.size - 1
            length = float(np.sum(np.linalg.norm(np.diff(x[piece[: j + 1]], axis=0), axis=1))) if j > 0 else 0.0
            if j >= 1 and (j == piece.size - 1 or length >= MIN_PIECE):
                part = piece[: j + 1]
                fp = _inverse(setting, face, x[part], float(s_first))
                v = np.diff(x[part], axis=0).sum(axis=0)
                out.append(Push(face, float(t[part[0]]), float(t[part[-1]]), float(np.arctan2(v[1], v[0])), part,
                                fp.tool_pose, contact_s=fp.s, recontact=False,
                                cone_margin=float(fp.cone_margin.min(initial=np.pi)), edge_margin=fp.edge_margin,
                                frame_s=framed))
                if part[-1] == idx[-1]:
                    return out
                a += part.size - 1
                continue
        step = max(1, piece.size // 60)  # the travel profile on every step-th sample (the final inverse is whole)
        coarse = np.unique(np.append(np.arange(0, piece.size, step), piece.size - 1))
        for _ in range(3):  # where the contact starts moves the tool, hence the heading: a fixed point
            travel = np.interp(np.arange(piece.size), coarse, _arc(setting, face, x[piece[coarse]], s0) - s0)
            j = _longest_fit(travel, width)
            part = piece[: j + 1]
            new = mid - 0.5 * (travel[: j + 1].max() + travel[: j + 1].min())
            if abs(new - s0) < 2e-5:  # 20 um: the final inverse below is exact, the margin is 500 um
                break
            s0 = new
        if part.size < 2:  # not even one step fits on the face
            raise PushRefused(
                f"face {face!r} cannot carry the object's motion from t = {t[part[0]]:.2f} s (object at "
                f"{np.round(x[part[0]], 4).tolist()} m): one step of the path rolls the contact across more "
                f"than the {1e3 * width:.1f} mm of usable face")
        fp = _inverse(setting, face, x[part], s0)
        if setting.obstacles:  # the tool's body is not in the fit: a start that keeps it off the obstacles
            fp, s0 = _clear_start(setting, face, x[part], fp, s0, lo, hi)
        off = np.flatnonzero((fp.s < lo - 1e-6) | (fp.s > hi + 1e-6))
        if off.size and off[0] >= 2:  # the fixed point left a sliver outside: end the contact before it
            part = part[: off[0]]
            fp = _inverse(setting, face, x[part], s0)
        last = part[-1] == idx[-1]
        length = float(np.sum(np.linalg.norm(np.diff(x[part], axis=0), axis=1)))
        if not last and length < MIN_PIECE:
            raise PushRefused(
                f"face {face!r} cannot carry the object's motion from t = {t[part[0]]:.2f} s (object at "
                f"{np.round(x[part[0]], 4).tolist()} m): its contact would leave the face within "
                f"{1e3 * length:.2f} mm of travel (sideways motion or heading turn too fast for the "
                f"{1e3 * width:.1f} mm of usable face)")
        v = np.diff(x[part], axis=0).sum(axis=0)
        out.append(Push(face, float(t[part[0]]), float(t[part[-1]]), float(np.arctan2(v[1], v[0])), part,
                        fp.tool_pose, contact_s=fp.s, recontact=bool(out),
                        cone_margin=float(fp.cone_margin.min(initial=np.pi)), edge_margin=fp.edge_margin,
                        frame_s=framed))
        if last:
            return out
        a += part.size - 1


def realise_pushes(setting: Setting, spans: Sequence[tuple[str, NDArray[np.intp]]], t: NDArray[np.float64],
                   x: NDArray[np.float64], limits: ContactLimits, s_first: float | None = None) -> tuple[Push, ...]:
    """Every span's pushes, in order (see :func:`realise_span`; ``s_first`` for the first span);
    raises :class:`PushRefused`."""
    pushes: list[Push] = []
    for i, (face, idx) in enumerate(spans):
        pushes += realise_span(setting, face, t, x, idx, limits, s_first if i == 0 else None)
    return tuple(pushes)
