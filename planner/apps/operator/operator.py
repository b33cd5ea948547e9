"""A scripted, human-like operator pushing the puck with tool 1 on the simulated Omni.

The script follows the demonstration task (:data:`tooltransfer.problems.demo_scene.DEMO_SCENE`): forward pushes with
the upper face, leftward pushes with the left face, a corner where the face changes, and between two
faces an arching tool move round the puck (Fig. 9a: back off, go round, approach the other face's
contact point), bulging out until the swept tool outline keeps its clearance from the puck and from
the obstacles (checked with shapely at the heading the Omni imposes).

Human-like: a pause before starting; minimum-jerk moves; each push a stroke that meets the puck
moving (placed ``APPROACH`` behind it) and turns into an ease-off before it ends (two overlapping
minimum-jerk submovements); a dwell at each corner; corners, speeds, dwells and overlaps varied per
demonstration (seeded); a smooth hand tremor. It watches the puck: each leg is pushed in chunks of
at most ``CHUNK``, after each chunk it observes where the puck is and re-aims towards the corner with
the face's actual push direction at the pose the Omni gives it (the heading turns with the waist,
so the puck drifts along the face), keeping within the face's cone; at the end it adds short
pushes until the puck is in the target square. A demonstration where the tool touches the puck
outside a push, or the arm is held by something, fails (:class:`DemonstrationFailed`), as a person
would start again.

The ground truth: pushes are the simulator's contact spans of each push stroke (``MIN_CONTACT``,
``MERGE_GAP``), switches the script's switching moves, corners the puck's centre during each switch.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline

from tooltransfer.errors import InputError, ToolTransferError
from tooltransfer.planner.planning.ss.arch_variant import swept_clearance
from tooltransfer.problems.demo_scene import DEMO_SCENE, DemoScene
from tooltransfer.tools.contact import contact_on_platform
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.model import Tool
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import Pose2D, wrap_angle
from tooltransfer.tools.sim import ContactEvent, Execution, Rates, SimPlatform

BACK_OFF = 0.012
"""How far [m] the tool backs off a face's contact before going round the puck."""
CLEARANCE = 0.004
"""Least tool-puck clearance [m] the operator keeps while going round it."""
CHUNK = 0.015
"""Longest push [m] before the operator looks at the puck again."""
APPROACH = 0.003
"""How far [m] behind the puck the operator places a face before pushing through it (the face
meets the puck moving, not from rest)."""
EASE_OFF = 0.003
"""How far [m] the operator eases off the puck after each push before looking at it."""
OBSTACLE_CLEARANCE = 0.003
"""Least clearance [m] between the tool and the obstacles on a switch."""
TREMOR = 0.00015
"""Hand tremor [m]: standard deviation of a smooth random offset with knots about 0.1 s apart."""
MIN_CONTACT, MERGE_GAP = 0.05, 0.2
"""Ground truth of a push: the simulator's contact events of one face, with breaks shorter than
``MERGE_GAP`` [s] bridged; spans shorter than ``MIN_CONTACT`` [s] are touches, not pushes (the same
rules as :func:`tooltransfer.planner.learning.segmentation.segment`'s defaults)."""
SNAG = 0.02
"""Joint tracking error [rad] above which the arm is held by something (a failed demonstration)."""


class DemonstrationFailed(ToolTransferError):
    """The scripted operator could not finish a demonstration (a seed to skip)."""


@dataclass(frozen=True)
class Truth:
    """Ground truth of one demonstration: pushes ``(face, t_start, t_end)`` (the simulator's contact
    spans, see ``MIN_CONTACT``), switches ``(from_face, to_face, t_start, t_end)`` [s] (the script's
    switching moves) and the object's centre (2,) [m] during each switch (the corners)."""

    pushes: tuple[tuple[str, float, float], ...]
    switches: tuple[tuple[str, str, float, float], ...]
    corners: tuple[tuple[float, float], ...] = ()


@dataclass
class _Log:
    parts: list[Execution] = field(default_factory=list)
    pushes: list[tuple[str, float, float]] = field(default_factory=list)
    switches: list[tuple[str, str, float, float]] = field(default_factory=list)
    corners: list[tuple[float, float]] = field(default_factory=list)


def _min_jerk(a: NDArray[np.float64], b: NDArray[np.float64], dur: float, dt: float = 0.01) -> tuple:
    n = max(3, int(np.ceil(dur / dt)) + 1)
    s = np.linspace(0.0, 1.0, n)
    prof = s**3 * (10 - 15 * s + 6 * s**2)
    return np.linspace(0.0, dur, n), a + prof[:, None] * (b - a)


def _spans(contacts: tuple[ContactEvent, ...]) -> list[tuple[float, float]]:
    """Contact spans [s] of the events: breaks under ``MERGE_GAP`` bridged, spans under
    ``MIN_CONTACT`` dropped."""
    spans: list[list[float]] = []
    for e in contacts:
        if spans and e.t_start - spans[-1][1] < MERGE_GAP:
            spans[-1][1] = max(spans[-1][1], e.t_end)
        else:
            spans.append([e.t_start, e.t_end])
    return [(a, b) for a, b in spans if b - a >= MIN_CONTACT]


def _stroke(start: NDArray[np.float64], d: NDArray[np.float64], length: float, dur: float,
            rng: np.random.Generator, dt: float = 0.01) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A push stroke and the ease-off after it, as two overlapping minimum-jerk submovements (the
    superposition model of human reaching, Flash and Henis 1991): forward by ``length`` [m] along
    the unit direction ``d`` (2,) in ``dur`` [s], then back by ``EASE_OFF`` in about 0.3 s, started
    a little before the push ends, so the hand turns round with some acceleration instead of
    stopping dead. Returns times (K,) [s] and points (K, 2) [m]."""
    back_dur = 0.3 * rng.uniform(0.9, 1.1)
    overlap = 0.18 * rng.uniform(0.8, 1.2)
    total = dur - overlap + back_dur
    t = np.linspace(0.0, total, int(np.ceil(total / dt)) + 1)

    def mj(u: NDArray[np.float64]) -> NDArray[np.float64]:
        u = np.clip(u, 0.0, 1.0)
        return u**3 * (10 - 15 * u + 6 * u**2)

    s = length * mj(t / dur) - EASE_OFF * mj((t - (dur - overlap)) / back_dur)
    return t, start + s[:, None] * d


class ScriptedOperator:
    """Generates demonstrations on the simulated platform.

    Args:
        scene: the demonstration task; tool: default tool 1 (``finger``); platform: the Omni.
        speed: nominal pushing speed [m/s]; tremor: hand tremor amplitude [m].
    """

    def __init__(
        self, scene: DemoScene = DEMO_SCENE, tool: Tool | None = None, platform: OmniPlatform | None = None,
        speed: float = 0.02, tremor: float = TREMOR,
    ) -> None:
        self.scene = scene
        self.tool = tool or load_tool("finger")
        self.platform = platform or OmniPlatform(a_t=self.tool.a_t)
        self.speed, self.tremor = speed, tremor

    # ------------------------------------------------------------------ geometry
    def _contact(self, face: str, obj: NDArray[np.float64], direction: float) -> tuple[Pose2D, float]:
        """Contact pose of ``face`` at the puck ``obj`` aiming at ``direction``, turned into the
        face's cone (minus 5 degrees) where the Omni's heading puts it outside; and that direction."""
        pc = contact_on_platform(self.tool, face, obj, direction, self.platform)
        if pc.contact is None:
            raise InputError("scene", f"a puck position where face {face!r} can be placed", obj.tolist())
        f = self.tool.face(face)
        limit = f.theta_b - np.radians(5.0)
        off = float(np.clip(pc.contact.cone_offset, -limit, limit))
        aim = pc.contact.pose.yaw + f.push_angle + off
        pc = contact_on_platform(self.tool, face, obj, aim, self.platform)
        return pc.contact.pose, aim

    def _keeps_clear(self, path: NDArray[np.float64], obj: NDArray[np.float64] | None) -> bool:
        """Whether the tool along ``path`` (K, 2) stays within reach, ``CLEARANCE`` off the puck at
        ``obj`` (unless None) and ``OBSTACLE_CLEARANCE`` off every obstacle (swept outline, shapely)."""
        if not np.all(joint_path(self.platform, path).violation == 0.0):
            return False
        if obj is not None and swept_clearance(self.tool, self.platform, path, obj) < CLEARANCE:
            return False
        return all(swept_clearance(self.tool, self.platform, path, o.centre, o.radius) >= OBSTACLE_CLEARANCE
                   for o in self.scene.obstacles)

    def _switch_path(self, here: NDArray[np.float64], a_back: NDArray[np.float64], b_back: NDArray[np.float64],
                     b: NDArray[np.float64], obj: NDArray[np.float64]) -> NDArray[np.float64]:
        """Whole switch path (K, 2): retreat ``here`` -> ``a_back``, arch round the puck at ``obj`` to
        ``b_back``, approach ``b``. The arch is polar about the puck
        (as :func:`tooltransfer.planner.planning.ss.arch_variant.arch_path`),
        the short way round first, bulging out until the swept tool keeps its clearance from the puck
        and from the obstacles (the tool's body reaches 30 mm behind its head, so an arch that clears
        the puck can still sweep the body over an obstacle)."""
        da, db = a_back - obj, b_back - obj
        ta, tb = np.arctan2(da[1], da[0]), np.arctan2(db[1], db[0])
        dth = wrap_angle(tb - ta)
        s = np.linspace(0.0, 1.0, 60)
        ends = (np.linspace(here, a_back, 12), np.linspace(b_back, b, 12))
        for bulge in np.arange(0.0, 0.06 + 1e-12, 0.004):
            for way in (dth, dth - np.copysign(2 * np.pi, dth)):
                r = (1 - s) * np.hypot(*da) + s * np.hypot(*db) + bulge * np.sin(np.pi * s)
                th = ta + s * way
                arch = obj + r[:, None] * np.column_stack([np.cos(th), np.sin(th)])
                path = np.vstack([ends[0], arch[1:-1], ends[1]])
                if self._keeps_clear(arch, obj) and self._keeps_clear(path, None):
                    return path
        raise DemonstrationFailed(f"no way round the puck at {np.round(obj, 4).tolist()} clear of the obstacles")

    # ------------------------------------------------------------------ moves
    def _run(self, sim: SimPlatform, log: _Log, t: NDArray[np.float64], xy: NDArray[np.float64],
             rng: np.random.Generator) -> Execution:
        if self.tremor > 0 and len(t) > 4:  # smooth hand tremor (knots ~0.1 s apart), zero at both ends
            u = (t - t[0]) / (t[-1] - t[0])
            knots = rng.normal(0.0, self.tremor, (max(4, int(np.ceil((t[-1] - t[0]) / 0.1)) + 1), 2))
            tremor = CubicSpline(np.linspace(0.0, 1.0, len(knots)), knots, axis=0)(u)
            xy = xy + tremor * np.sin(np.pi * u)[:, None]
        ex = sim.execute_tool_path(t, xy, rates=self.rates)
        if ex.tracking_error > SNAG:  # the tool caught on something: a person would start again
            raise DemonstrationFailed(f"the arm was held (tracking error {ex.tracking_error:.3f} rad)")
        log.parts.append(ex)
        return ex

    rates = Rates(object_hz=1000.0, tool_hz=1000.0)
    """Every physics step is recorded; the sensors' own clocks pick their samples from it
    (:func:`tooltransfer.planner.apps.operator.generate.record`), so their rates do not depend on how the operator's
    moves are cut into executions."""

    def demonstrate(self, seed: int) -> tuple[Execution, Truth]:
        """Run one demonstration; returns the noise-free recording and the ground truth."""
        rng = np.random.default_rng(seed)
        scene = self.scene
        corners = scene.corners + np.vstack([np.zeros(2), rng.normal(0.0, 0.002, (len(scene.corners) - 1, 2))])
        speed = self.speed * rng.uniform(0.8, 1.2)
        sim = SimPlatform(self.tool, self.platform, obstacles=list(scene.obstacles))
        log = _Log()
        obj = corners[0].copy()
        d0 = float(np.arctan2(*(corners[1] - obj)[::-1]))
        pose, aim = self._contact(scene.faces[0], obj, d0)
        contact = np.array([pose.x, pose.y])
        back = contact - BACK_OFF * np.array([np.cos(aim), np.sin(aim)])
        sim.reset(obj, tool_xy=back)
        settle = rng.uniform(0.8, 1.5)  # the operator takes the stylus and settles before starting
        self._run(sim, log, np.array([0.0, settle]), np.vstack([back, back]), rng)
        t, xy = _min_jerk(back, contact - APPROACH * np.array([np.cos(aim), np.sin(aim)]), 1.0)
        self._run(sim, log, t, xy, rng)
        face_prev: str | None = None
        legs = list(zip(scene.faces, corners[1:], strict=True))
        for face, goal in legs:
            obj, tool_pose = sim.observe()
            if face_prev is not None and face != face_prev:
                self._switch(sim, log, face_prev, face, obj, goal, rng)
            self._push_leg(sim, log, face, goal, speed, rng)
            dwell = rng.uniform(0.3, 0.7)
            here = sim.observe()[1][:2]
            self._run(sim, log, np.array([0.0, dwell]), np.vstack([here, here]), rng)
            face_prev = face
        for _ in range(3):  # corrections into the target square
            obj, _ = sim.observe()
            if scene.in_target(obj):
                break
            self._push_leg(sim, log, face_prev, scene.target, speed, rng, max_chunks=2)
        obj, tool_pose = sim.observe()
        yaw = tool_pose[2] + self.tool.face(face_prev).push_angle
        away = tool_pose[:2] - BACK_OFF * np.array([np.cos(yaw), np.sin(yaw)])
        t, xy = _min_jerk(tool_pose[:2], away, 0.8)
        self._run(sim, log, t, xy, rng)
        ex = Execution.concat(log.parts)
        return ex, Truth(tuple(self._merge(log.pushes)), tuple(log.switches), tuple(log.corners))

    def _switch(self, sim: SimPlatform, log: _Log, face_a: str, face_b: str, obj: NDArray[np.float64],
                goal: NDArray[np.float64], rng: np.random.Generator) -> None:
        t0 = sim.time
        here = sim.observe()[1]
        ya = here[2] + self.tool.face(face_a).push_angle
        a_back = here[:2] - BACK_OFF * np.array([np.cos(ya), np.sin(ya)])
        pose, aim = self._contact(face_b, obj, float(np.arctan2(*(goal - obj)[::-1])))
        b = np.array([pose.x, pose.y]) - APPROACH * np.array([np.cos(aim), np.sin(aim)])
        b_back = b - BACK_OFF * np.array([np.cos(aim), np.sin(aim)])
        path = self._switch_path(here[:2], a_back, b_back, b, obj)
        length = np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1))
        dur = max(1.5, 1.875 * length / 0.04) * rng.uniform(0.9, 1.2)
        seg = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
        t, s = _min_jerk(np.zeros(1), np.array([seg[-1]]), dur)
        xy = np.column_stack([np.interp(s[:, 0], seg, path[:, j]) for j in range(2)])
        if self._run(sim, log, t, xy, rng).contacts:
            raise DemonstrationFailed(f"touched the puck while switching from {face_a!r} to {face_b!r}")
        log.switches.append((face_a, face_b, t0, sim.time))
        log.corners.append((float(obj[0]), float(obj[1])))

    def _push_leg(self, sim: SimPlatform, log: _Log, face: str, goal: NDArray[np.float64], speed: float,
                  rng: np.random.Generator, max_chunks: int = 8) -> None:
        bias = 0.0  # how far the puck's motion turned from the aim last time (it rolls along the face)
        for _ in range(max_chunks):
            obj, tool_pose = sim.observe()
            to_goal = goal - obj
            dist = float(np.hypot(*to_goal))
            if dist < 0.002:
                return
            try:
                pose, aim = self._contact(face, obj, float(np.arctan2(to_goal[1], to_goal[0])) - bias)
            except InputError:  # the face cannot be placed there: the operator gives up this leg
                return
            d = np.array([np.cos(aim), np.sin(aim)])
            length = min(CHUNK, max(0.0, float(to_goal @ d)))
            if length < 0.002:
                return
            start = np.array([pose.x, pose.y]) - APPROACH * d
            if np.hypot(*(start - tool_pose[:2])) > 0.0005:  # re-place the face where the puck now is
                t, xy = _min_jerk(tool_pose[:2], start, 0.4)
                if self._run(sim, log, t, xy, rng).contacts:
                    raise DemonstrationFailed(f"touched the puck while placing face {face!r}")
            t, xy = _stroke(start, d, length + APPROACH, max(0.8, 1.875 * (length + APPROACH) / speed), rng)
            t0 = sim.time
            ex = self._run(sim, log, t, xy, rng)
            moved = sim.observe()[0] - obj
            if np.hypot(*moved) > 0.003:
                turn = float(np.angle(np.exp(1j * (np.arctan2(moved[1], moved[0]) - aim))))
                bias = float(np.clip(bias + 0.7 * turn, -0.6, 0.6))
            for a, b in _spans(ex.contacts):
                log.pushes.append((face, max(t0, a), b))

    @staticmethod
    def _merge(pushes: list[tuple[str, float, float]], gap: float = MERGE_GAP) -> list[tuple[str, float, float]]:
        """Consecutive push chunks of one face with contact gaps under ``gap`` [s] become one push."""
        out: list[tuple[str, float, float]] = []
        for face, a, b in pushes:
            if out and out[-1][0] == face and a - out[-1][2] < gap:
                out[-1] = (face, out[-1][1], b)
            else:
                out.append((face, a, b))
        return out
