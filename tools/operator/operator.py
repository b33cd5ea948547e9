"""A scripted, human-like operator pushing the puck with tool 1 on the simulated Omni.

The script follows the demonstration task (:mod:`tools.operator.scene`): forward pushes with the
upper face, leftward pushes with the left face, a corner where the face changes, and between two
faces an arching tool move round the puck (back off, go round at a clearance checked with shapely,
approach the other face's contact). Human-like: minimum-jerk moves, a dwell at each corner, corners,
speeds and dwells varied per demonstration (seeded), a little tremor on the hand. It watches the
puck: each leg is pushed in chunks, and after each chunk the operator observes where the puck is and
re-aims towards the corner within the face's cone (the heading turns with the waist, so the puck
drifts along the face); at the end it adds short pushes until the puck is in the target square.

The ground truth (faces and intervals of the pushes, intervals of the switches) comes from the
script's own timing and the simulator's contact events.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from dmp.errors import InputError
from tools.arch import NoArch, arch_path
from tools.contact import contact_on_platform
from tools.library import load_tool
from tools.model import Tool
from tools.omni.platform import OmniPlatform
from tools.operator.scene import DEMO_SCENE, DemoScene
from tools.pose import Pose2D
from tools.sim import Execution, Rates, SimPlatform

BACK_OFF = 0.012
"""How far [m] the tool backs off a face's contact before going round the puck."""
CLEARANCE = 0.004
"""Least tool-puck clearance [m] the operator keeps while going round it."""
CHUNK = 0.015
"""Longest push [m] before the operator looks at the puck again."""
EASE_OFF = 0.003
"""How far [m] the operator eases off the puck after each push before looking at it."""


class DemonstrationFailed(Exception):
    """The scripted operator could not finish a demonstration (a seed to skip)."""


@dataclass(frozen=True)
class Truth:
    """Ground truth of one demonstration: pushes ``(face, t_start, t_end)`` and switches
    ``(from_face, to_face, t_start, t_end)`` [s]."""

    pushes: tuple[tuple[str, float, float], ...]
    switches: tuple[tuple[str, str, float, float], ...]


@dataclass
class _Log:
    parts: list[Execution] = field(default_factory=list)
    pushes: list[tuple[str, float, float]] = field(default_factory=list)
    switches: list[tuple[str, str, float, float]] = field(default_factory=list)


def _min_jerk(a: NDArray[np.float64], b: NDArray[np.float64], dur: float, dt: float = 0.01) -> tuple:
    n = max(3, int(np.ceil(dur / dt)) + 1)
    s = np.linspace(0.0, 1.0, n)
    prof = s**3 * (10 - 15 * s + 6 * s**2)
    return np.linspace(0.0, dur, n), a + prof[:, None] * (b - a)


class ScriptedOperator:
    """Generates demonstrations on the simulated platform.

    Args:
        scene: the demonstration task; tool: default tool 1 (``finger``); platform: the Omni.
        speed: nominal pushing speed [m/s]; tremor: hand tremor amplitude [m].
    """

    def __init__(
        self, scene: DemoScene = DEMO_SCENE, tool: Tool | None = None, platform: OmniPlatform | None = None,
        speed: float = 0.02, tremor: float = 0.0003,
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

    def _arch(self, a: NDArray[np.float64], b: NDArray[np.float64], obj: NDArray[np.float64]) -> NDArray[np.float64]:
        try:
            return arch_path(self.tool, self.platform, a, b, obj, CLEARANCE)
        except NoArch as exc:
            raise DemonstrationFailed(str(exc)) from None

    # ------------------------------------------------------------------ moves
    def _run(self, sim: SimPlatform, log: _Log, t: NDArray[np.float64], xy: NDArray[np.float64],
             rng: np.random.Generator) -> Execution:
        if self.tremor > 0 and len(t) > 4:  # smooth hand tremor, zero at both ends
            k = len(t)
            noise = rng.normal(0.0, self.tremor, (k // 10 + 2, 2))
            tremor = np.column_stack([np.interp(np.linspace(0, 1, k), np.linspace(0, 1, len(noise)), noise[:, j])
                                      for j in range(2)])
            xy = xy + tremor * np.sin(np.pi * np.linspace(0, 1, k))[:, None]
        ex = sim.execute_tool_path(t, xy, rates=self.rates)
        log.parts.append(ex)
        return ex

    rates = Rates(object_hz=30.0, tool_hz=100.0)

    def demonstrate(self, seed: int) -> tuple[Execution, Truth]:
        """Run one demonstration; returns the noise-free recording and the ground truth."""
        rng = np.random.default_rng(seed)
        scene = self.scene
        corners = scene.corners + np.vstack([np.zeros(2), rng.normal(0.0, 0.002, (len(scene.corners) - 1, 2))])
        speed = self.speed * rng.uniform(0.8, 1.2)
        sim = SimPlatform(self.tool, self.platform, obstacles=[scene.obstacle])
        log = _Log()
        obj = corners[0].copy()
        d0 = float(np.arctan2(*(corners[1] - obj)[::-1]))
        pose, aim = self._contact(scene.faces[0], obj, d0)
        contact = np.array([pose.x, pose.y])
        back = contact - BACK_OFF * np.array([np.cos(aim), np.sin(aim)])
        sim.reset(obj, tool_xy=back)
        t, xy = _min_jerk(back, contact - 0.001 * np.array([np.cos(aim), np.sin(aim)]), 1.0)
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
        return ex, Truth(tuple(self._merge(log.pushes, ex)), tuple(log.switches))

    def _switch(self, sim: SimPlatform, log: _Log, face_a: str, face_b: str, obj: NDArray[np.float64],
                goal: NDArray[np.float64], rng: np.random.Generator) -> None:
        t0 = sim.time
        here = sim.observe()[1]
        ya = here[2] + self.tool.face(face_a).push_angle
        a_back = here[:2] - BACK_OFF * np.array([np.cos(ya), np.sin(ya)])
        pose, aim = self._contact(face_b, obj, float(np.arctan2(*(goal - obj)[::-1])))
        b = np.array([pose.x, pose.y]) - 0.001 * np.array([np.cos(aim), np.sin(aim)])
        b_back = b - BACK_OFF * np.array([np.cos(aim), np.sin(aim)])
        arch = self._arch(a_back, b_back, obj)
        path = np.vstack([_min_jerk(here[:2], a_back, 0.6)[1], arch[1:], _min_jerk(b_back, b, 0.6)[1][1:]])
        length = np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1))
        dur = max(1.5, 1.875 * length / 0.04) * rng.uniform(0.9, 1.2)
        seg = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
        t, s = _min_jerk(np.zeros(1), np.array([seg[-1]]), dur)
        xy = np.column_stack([np.interp(s[:, 0], seg, path[:, j]) for j in range(2)])
        self._run(sim, log, t, xy, rng)
        log.switches.append((face_a, face_b, t0, sim.time))

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
            start = np.array([pose.x, pose.y]) - 0.001 * d
            if np.hypot(*(start - tool_pose[:2])) > 0.0005:  # re-place the face where the puck now is
                t, xy = _min_jerk(tool_pose[:2], start, 0.4)
                self._run(sim, log, t, xy, rng)
            t, xy = _min_jerk(start, start + (length + 0.001) * d, max(0.8, 1.875 * length / speed))
            t0 = sim.time
            ex = self._run(sim, log, t, xy, rng)
            end = xy[-1]
            t_back, xy_back = _min_jerk(end, end - EASE_OFF * d, 0.3)  # ease off the puck before looking
            ex = Execution.concat([ex, self._run(sim, log, t_back, xy_back, rng)])
            moved = sim.observe()[0] - obj
            if np.hypot(*moved) > 0.003:
                turn = float(np.angle(np.exp(1j * (np.arctan2(moved[1], moved[0]) - aim))))
                bias = float(np.clip(bias + 0.7 * turn, -0.6, 0.6))
            touching = [(e.t_start, e.t_end) for e in ex.contacts if e.t_end - e.t_start > 0.05]
            if touching:
                log.pushes.append((face, max(t0, touching[0][0]), touching[-1][1]))

    @staticmethod
    def _merge(pushes: list[tuple[str, float, float]], ex: Execution, gap: float = 0.2) -> list:
        """Consecutive push chunks of one face with contact gaps under ``gap`` [s] become one push."""
        out: list[tuple[str, float, float]] = []
        for face, a, b in pushes:
            if out and out[-1][0] == face and a - out[-1][2] < gap:
                out[-1] = (face, out[-1][1], b)
            else:
                out.append((face, a, b))
        return out
