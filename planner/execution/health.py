"""Sensor health of the closed loop: robust looks at the object, and the checks that tell a faulty
camera, arm or world from a mispredicting push model.

A **look** (:func:`take_look`) asks the camera for ``frames`` frames. Unusable frames (dropped:
not finite, the wrong shape, or the call raised) are taken again, at most as many as the look asks
for before the run ends with ``sensor_fault``. A look whose frames spread more than
:data:`NOISY_FACTOR` times the camera's declared noise takes more frames, so that its mean is as
precise as the declared camera's (at most :data:`MAX_LOOK_FACTOR` times ``frames``). Frames farther
than :data:`OUTLIER_SIGMAS` standard deviations (the declared noise or the measured spread, the
larger) from the frames' median are outliers, left out of the mean; without any the mean of all.

:class:`Health` then judges each look against what the loop knows:

* the camera is **frozen** when a look repeats the previous one exactly (a camera's noise never
  does) while the push model predicted at least :data:`FROZEN_TRAVEL` of travel in between, or
  when a look repeats one frame exactly from a camera declared noisy that showed its noise in an
  earlier look (a noise-free simulated camera never does), or
  when the reported tool outline reaches more than :data:`PENETRATION` into the object where the
  camera sees it (the camera sees the object where the tool is): ``sensor_fault``;
* the tool does **not follow** its command when the reported pose ends farther than
  :data:`TRACK_BOUND` from the commanded end: ``tracking_fault``; a steady offset within the bound
  (:attr:`Health.bias`) is commanded against by the loop, and the envelope checks both the command
  and the path the tool takes with that offset;
* the object was **displaced by something else** when it moved more than :data:`DISTURB_GATE` off
  the push model's prediction since the last look (the innovation) into the plan's safety margin
  of an obstacle, where the model put it outside: the run ends ``disturbed``; elsewhere, beyond
  :data:`DISTURB_GATE` and :data:`DISTURB_SHARE` of the predicted travel, it is noted and the loop
  re-plans from where the object is seen (its re-plan threshold does that).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.planner.execution.loop_stop import Disturbed, LoopStop, SensorFault, TrackingFault
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc, Obstacle

#: A frame farther than this many standard deviations from the frames' median is an outlier.
OUTLIER_SIGMAS = 6.0
#: A look whose frames spread more than this many times the declared noise takes more frames.
NOISY_FACTOR = 3.0
#: The most frames of a look, in multiples of the frames asked for.
MAX_LOOK_FACTOR = 50
#: Predicted object travel [m] past which an exactly repeated look means a frozen camera.
FROZEN_TRAVEL = 0.001
#: Depth [m] of the reported tool outline in the observed object past which the camera is wrong.
PENETRATION = 0.005
#: Distance [m] of the reported tool position from the commanded end past which the tool does not
#: follow its command.
TRACK_BOUND = 0.005
#: Commands whose end deviations estimate the arm's steady tracking offset (:attr:`Health.bias`).
BIAS_MOVES = 3
#: A tracking offset [m] below this is left alone (a tracking loop's own error).
BIAS_MIN = 0.0005
#: The object's displacement off the push model's prediction [m] past which something else moved it
#: (plus :data:`DISTURB_SHARE` of the predicted travel).
DISTURB_GATE = 0.004
#: The share of a push's predicted travel added to :data:`DISTURB_GATE` (a push model mispredicts in
#: proportion to the travel).
DISTURB_SHARE = 0.5
#: Smallest standard deviation [m] the outlier gate assumes (a camera declared noise-free).
MIN_SIGMA = 1e-4


@dataclass(frozen=True)
class Look:
    """One look: ``mean`` (2,) [m], the usable ``frames`` (N, 2) [m], the ``outliers`` left out and
    the unusable frames ``dropped``."""

    mean: NDArray[np.float64]
    frames: NDArray[np.float64]
    outliers: int
    dropped: int


def _spread(frames: NDArray[np.float64]) -> float:
    """A robust per-axis standard deviation [m] of ``frames`` (N, 2): the median distance from the
    median over that of a 2-D normal (sigma * sqrt(2 ln 2))."""
    d = np.linalg.norm(frames - np.median(frames, axis=0), axis=1)
    return float(np.median(d) / np.sqrt(2.0 * np.log(2.0)))


def take_look(frame: Callable[[], NDArray[np.float64]], frames: int, noise: float) -> Look:
    """A look of ``frames`` frames from ``frame()`` (module docstring); ``noise``: the camera's
    declared standard deviation per frame [m]. Raises :class:`SensorFault` when more frames are
    unusable than the look asks for (the last one's reason)."""
    got: list[NDArray[np.float64]] = []
    dropped = 0

    def fill(n: int) -> None:
        nonlocal dropped
        while len(got) < n:
            try:
                got.append(frame())
            except LoopStop as bad:
                dropped += 1
                if dropped > n:
                    raise SensorFault(f"{dropped} unusable camera frames in one look, the last: {bad.reason}",
                                      status="failed" if bad.status == "failed" else None) from bad

    fill(frames)
    spread = _spread(np.array(got)) if len(got) >= 3 else 0.0
    if noise > 0 and spread > NOISY_FACTOR * noise:
        fill(min(MAX_LOOK_FACTOR * frames, int(np.ceil(frames * (spread / noise) ** 2))))
        spread = _spread(np.array(got))
    arr = np.array(got)
    sigma = max(noise, spread, MIN_SIGMA)
    keep = np.linalg.norm(arr - np.median(arr, axis=0), axis=1) <= OUTLIER_SIGMAS * sigma
    if keep.all():
        return Look(np.mean(got, axis=0), arr, 0, dropped)
    return Look(arr[keep].mean(axis=0), arr[keep], int(np.sum(~keep)), dropped)


def penetration(tool: Tool, pose: NDArray[np.float64], centre: NDArray[np.float64], radius: float) -> float:
    """How deep [m] the tool outline at ``pose`` (3,) reaches into the disc of ``radius`` [m] at
    ``centre`` (2,) (negative: the gap between them)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    ring = np.asarray(tool.outline.exterior.coords)
    poly = shapely.Polygon(pose[:2] + ring @ np.array([[c, s], [-s, c]]))
    p = shapely.Point(centre)
    d = float(poly.exterior.distance(p))
    return radius + d if poly.contains(p) else radius - d


def obstacle_gap(obstacles: Sequence[Obstacle], centre: NDArray[np.float64], radius: float) -> float:
    """Least distance [m] between the object's disc at ``centre`` and the obstacles (inf without)."""
    disc = shapely.Point(centre).buffer(radius, quad_segs=32)
    return min((float(shapely.distance(disc, ob.polygon() if isinstance(ob, Disc) else ob)) for ob in obstacles),
               default=float("inf"))


class Health:
    """The judgements of the module docstring over one run.

    Args:
        tool: the tool; radius: the object's radius [m]; obstacles and margin [m]: the plan's;
        noise: the camera's declared noise per frame [m].
    """

    def __init__(self, tool: Tool, radius: float, obstacles: Sequence[Obstacle], margin: float,
                 noise: float = 0.0) -> None:
        self.tool, self.radius, self.obstacles, self.margin = tool, radius, tuple(obstacles), margin
        self.noise = noise
        self.noisy = False  # a look has shown the camera's noise
        self.last: Look | None = None
        self.predicted = np.zeros(2)
        self.notes: list[str] = []
        self.deviations: list[NDArray[np.float64]] = []
        self.innovations: list[tuple[float, float]] = []

    @property
    def bias(self) -> NDArray[np.float64] | None:
        """The arm's steady tracking offset (2,) [m]: the median of the last :data:`BIAS_MOVES`
        commands' end deviations (reported less commanded) when it exceeds :data:`BIAS_MIN`, else None."""
        if len(self.deviations) < BIAS_MOVES:
            return None
        b = np.median(self.deviations[-BIAS_MOVES:], axis=0)
        return b if float(np.hypot(*b)) > BIAS_MIN else None

    def pushed(self, displacement: NDArray[np.float64]) -> None:
        """A push chunk was sent that the push model says moves the object by ``displacement`` (2,) [m]."""
        self.predicted = self.predicted + displacement

    def moved(self, commanded: NDArray[np.float64], reported: NDArray[np.float64]) -> None:
        """A command ending at ``commanded`` (3,) was tracked; the tool reports ``reported`` (3,)."""
        self.deviations.append(reported[:2] - commanded[:2])
        off = float(np.hypot(*self.deviations[-1]))
        if off > TRACK_BOUND:
            raise TrackingFault(f"the tool reports {np.round(reported[:2], 4).tolist()} m, {1e3 * off:.1f} mm from "
                                f"its command's end {np.round(commanded[:2], 4).tolist()} m "
                                f"(bound {1e3 * TRACK_BOUND:.0f} mm)")

    def looked(self, look: Look, tool_pose: NDArray[np.float64]) -> None:
        """Judge ``look`` with the tool reported at ``tool_pose`` (3,); raises the fault it shows."""
        o = look.mean
        if look.outliers or look.dropped:
            self.notes.append(f"a look left out {look.outliers} outlier and {look.dropped} unusable frames")
        deep = penetration(self.tool, tool_pose, o, self.radius)
        if deep > PENETRATION:
            raise SensorFault(f"the camera sees the object at {np.round(o, 4).tolist()} m, {1e3 * deep:.1f} mm "
                              f"inside the tool's outline (frozen or displaced frames)")
        still = len(look.frames) >= 3 and np.ptp(look.frames, axis=0).max() == 0.0
        if still and self.noisy and self.noise > 0.0:
            raise SensorFault(f"the camera repeats one frame exactly over a look of {len(look.frames)} frames "
                              f"although it showed its noise ({1e3 * self.noise:.1f} mm) before (a frozen camera)")
        self.noisy = self.noisy or not still
        last, predicted = self.last, self.predicted
        self.last, self.predicted = look, np.zeros(2)
        if last is None:
            return
        travel = float(np.hypot(*predicted))
        same = np.array_equal(look.frames[:1], last.frames[:1]) and still
        if same and travel >= FROZEN_TRAVEL:
            raise SensorFault(f"the camera's frames did not change while the push model predicts "
                              f"{1e3 * travel:.1f} mm of travel (a frozen camera)")
        innovation = float(np.hypot(*(o - last.mean - predicted)))
        self.innovations.append((travel, innovation))
        if innovation <= DISTURB_GATE:
            return
        where = f"{np.round(o, 4).tolist()} m, {1e3 * innovation:.1f} mm off the push model's prediction"
        gap = obstacle_gap(self.obstacles, o, self.radius)
        if gap < self.margin <= obstacle_gap(self.obstacles, last.mean + predicted, self.radius):
            raise Disturbed(f"the object was displaced to {where}, {1e3 * gap:.1f} mm from an obstacle "
                            f"(margin {1e3 * self.margin:.1f} mm)")
        if innovation > DISTURB_GATE + DISTURB_SHARE * travel:
            self.notes.append(f"the object was displaced to {where}: re-planning from there")
