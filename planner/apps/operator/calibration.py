"""Calibration recordings: straight pushes at several angles off a face's normal, for identifying
the push mechanics ``mu`` and ``c`` (docs/design.md section 10, :mod:`tooltransfer.tools.pushing.identify`).

Why: the demonstrations push near the faces' normals, where the puck goes along the normal
whatever ``c`` is, and their contacts stick, where ``mu`` does not act. A calibration pushes the
puck on purpose at angles ``alpha`` off the normal (at the heading the Omni has at the contact):

* sticking trials, ``alpha`` in 0, +-15, +-30, +-45 degrees on every face: the puck turns off the
  normal by ``atan(tan(alpha) / (1 + 1/c^2))`` and identifies ``c``;
* sliding trials, ``alpha`` = +-80 degrees on the longest face: beyond ``atan(mu (1 + 1/c^2))``
  (72 degrees with the platform's values; 80 degrees slides for ``mu`` up to about 1.5) the contact
  slides and the puck moves at ``atan(mu)`` off the normal, which identifies ``mu``.

A trial places the puck by hand (:meth:`SimPlatform.reset`), then pushes it in strokes (the
demonstrations' stroke: minimum-jerk, meeting the puck moving, easing off), each re-aimed from
where the operator sees the puck, until it has moved ``travel`` (20 mm by default). A sticking
contact slides along the face, relative to the tool, by ``(1 - 1/kappa)`` of the tool's sideways
travel (0.13-0.66 mm per mm of tool travel at 10-60 degrees with c = 0.59), a sliding one by less
than the tool's sideways travel: so each stroke starts its contact ``MARGIN`` from the face's end
it moves away from and is at most as long as keeps the tool's sideways travel within the face
(``L |sin alpha| <= usable length``, a bound that needs no knowledge of ``c``), so the contact stays
on the face; at most ``STROKE`` long. The operator pauses after each stroke so the camera sees the
puck at rest (the identification's rest positions). Each trial is one recording (one CSV of the
dataset format); the ground truth names each trial's face and angle and each stroke's contact span.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.operator.generate import JOINT_STEP, OBJECT_NOISE, RATES, platform_meta, record
from tooltransfer.planner.apps.operator.operator import (
    APPROACH,
    BACK_OFF,
    DemonstrationFailed,
    ScriptedOperator,
    _Log,
    _min_jerk,
    _spans,
    _stroke,
)
from tooltransfer.problems.dataset import Demonstration, Meta, write_dataset
from tooltransfer.tools.contact import contact_on_platform
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import OBJECT_RADIUS
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim import Execution, SimPlatform

ANGLES_DEG = (0, 15, -15, 30, -30, 45, -45)
"""Sticking trials' angles off the normal [deg], on every face."""
SLIDE_ANGLES_DEG = (80, -80)
"""Sliding trials' angles off the normal [deg], on the longest face."""
TRAVEL = 0.02
"""How far [m] each trial moves the puck (the sum of its strokes)."""
STROKE = 0.015
"""Longest stroke [m] of the tool through the puck before the operator looks again."""
MARGIN = 0.0005
"""How far [m] from a face's end each stroke's contact starts."""
MIN_STROKE = 0.002
"""Shortest stroke [m]."""
NORMAL_SPEED = 0.5
"""Least fraction of the nominal speed a stroke keeps along the face's normal (steep strokes go faster)."""
MAX_STROKES = 14
"""Strokes per trial at most (the upper face at 45 degrees needs about 9 for 20 mm)."""
START = {"along": (0.0, 0.14), "across": (0.025, 0.15)}
"""Where [m] the puck is placed for a trial: ``along`` for a face whose normal points away from
the Omni (it pushes the puck outwards), ``across`` for one pushing sideways (leftwards)."""


class CalibrationFailed(DemonstrationFailed):
    """A calibration trial could not be finished (a seed to skip)."""


@dataclass(frozen=True)
class Trial:
    """One calibration trial: straight pushes with ``face`` at ``angle`` [rad] off its normal."""

    face: str
    angle: float

    @property
    def name(self) -> str:
        """The recording's name, e.g. ``left_p15`` (``m`` for negative angles)."""
        deg = round(np.degrees(self.angle))
        return f"{self.face}_{'m' if deg < 0 else 'p'}{abs(deg):02d}"


def default_trials(tool: Tool, angles_deg: tuple[float, ...] = ANGLES_DEG,
                   slide_angles_deg: tuple[float, ...] = SLIDE_ANGLES_DEG) -> list[Trial]:
    """The default protocol: every face at ``angles_deg``, the longest face also at ``slide_angles_deg``."""
    longest = max(tool.faces, key=lambda f: f.length).name
    trials = [Trial(f.name, float(np.radians(a))) for f in tool.faces for a in angles_deg]
    return trials + [Trial(longest, float(np.radians(a))) for a in slide_angles_deg]


class CalibrationOperator(ScriptedOperator):
    """The scripted operator of :mod:`tooltransfer.planner.apps.operator.operator` running calibration trials.

    Args:
        tool: the tool (default tool 1); platform: the Omni; speed: nominal stroke speed [m/s];
        travel: how far [m] each trial moves the puck.
    """

    def __init__(self, tool: Tool | None = None, platform: OmniPlatform | None = None, speed: float = 0.02,
                 travel: float = TRAVEL) -> None:
        super().__init__(tool=tool, platform=platform, speed=speed)
        self.travel = travel
        self._sim: SimPlatform | None = None

    def _stroke_plan(self, trial: Trial, obj: NDArray[np.float64], remaining: float
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], float, float]:
        """Where the next stroke starts (2,) [m], its unit direction (2,), its length [m] through the
        puck at ``obj`` (2,) [m], and the contact's start fraction on the face."""
        f = self.tool.face(trial.face)
        s0, s1 = f.contact_range
        usable = (s1 - s0) * f.length
        m = min(MARGIN, 0.25 * usable) / f.length
        lateral = np.array([-f.normal[1], f.normal[0]])  # t = J n in the tool frame
        ahead = float((f.end - f.start) @ lateral)  # > 0: s grows along t
        sn = np.sin(trial.angle)
        if abs(sn) < 1e-9:
            s = 0.5 * (s0 + s1)
        else:  # the contact moves along -t (relative to the tool) when the tool moves along +t
            s = (s1 - m) if (sn > 0) == (ahead > 0) else (s0 + m)
        pc = contact_on_platform(self.tool, trial.face, obj, 0.0, self.platform, s=s)
        if pc.contact is None:
            raise CalibrationFailed(f"the Omni cannot place face {trial.face!r} at {np.round(obj, 4).tolist()}")
        c = pc.contact
        normal = float(np.arctan2(*c.normal[::-1]))
        d = np.array([np.cos(normal + trial.angle), np.sin(normal + trial.angle)])
        length = STROKE
        if abs(sn) > 1e-9:
            length = min(length, (usable - 2 * m * f.length) / abs(sn))
        length = max(MIN_STROKE, min(length, remaining / max(np.cos(trial.angle), 0.2)))
        return c.pose.position - APPROACH * d, d, length, s

    def run_trial(self, trial: Trial, start: NDArray[np.float64], seed: int) -> tuple[Execution, dict]:
        """Run one trial from the puck placed at ``start`` (2,) [m]; returns the noise-free
        recording and its ground truth (face, angle, strokes with their contact spans)."""
        rng = np.random.default_rng(seed)
        if self._sim is None:
            self._sim = SimPlatform(self.tool, self.platform)
        sim = self._sim
        log = _Log()
        # the speed along the face's normal times the contact (segmentation): keep it at least
        # NORMAL_SPEED of the nominal speed, so hand tremor does not stall a steep stroke
        speed = self.speed * rng.uniform(0.8, 1.2) * max(1.0, NORMAL_SPEED / np.cos(trial.angle))
        first, d, _, _ = self._stroke_plan(trial, start, self.travel)
        back = first - (BACK_OFF - APPROACH) * d
        sim.reset(start, tool_xy=back)
        self._run(sim, log, np.array([0.0, rng.uniform(0.8, 1.2)]), np.vstack([back, back]), rng)
        t, xy = _min_jerk(back, first, 1.0)
        self._run(sim, log, t, xy, rng)
        strokes: list[dict] = []
        for _ in range(MAX_STROKES):
            obj, pose = sim.observe()
            remaining = self.travel - float(np.hypot(*(obj - start)))
            if remaining < 0.001:
                break
            here, d, length, s = self._stroke_plan(trial, obj, remaining)
            if np.hypot(*(here - pose[:2])) > 0.0005:  # re-place the face where the puck now is
                t, xy = _min_jerk(pose[:2], here, 0.4 * rng.uniform(0.9, 1.2))
                if self._run(sim, log, t, xy, rng).contacts:
                    raise CalibrationFailed(f"touched the puck while placing face {trial.face!r}")
            t, xy = _stroke(here, d, length + APPROACH, max(0.8, 1.875 * (length + APPROACH) / speed), rng)
            t0 = sim.time
            ex = self._run(sim, log, t, xy, rng)
            spans = _spans(ex.contacts)
            pause = sim.observe()[1][:2]  # the operator looks at the resting puck
            self._run(sim, log, np.array([0.0, rng.uniform(0.3, 0.5)]), np.vstack([pause, pause]), rng)
            if spans:
                strokes.append({"t_start": round(max(t0, spans[0][0]), 6), "t_end": round(spans[-1][1], 6),
                                "length": round(float(length), 6), "contact_s": round(float(s), 4)})
        obj, pose = sim.observe()
        away = pose[:2] - BACK_OFF * d
        t, xy = _min_jerk(pose[:2], away, 0.8)
        self._run(sim, log, t, xy, rng)
        ex = Execution.concat(log.parts)
        truth = {"face": trial.face, "angle_deg": round(float(np.degrees(trial.angle)), 6), "operator_seed": seed,
                 "object_start": [round(float(v), 6) for v in start],
                 "final_object_xy": [round(float(v), 6) for v in ex.object_xy[-1]],
                 "pushes": [{"face": trial.face, **s} for s in strokes]}
        return ex, truth

    def trial_start(self, trial: Trial, rng: np.random.Generator) -> NDArray[np.float64]:
        """Where the puck is placed for ``trial`` (2,) [m]: :data:`START` by the face's push
        direction at the neutral heading, a few millimetres of seeded scatter."""
        f = self.tool.face(trial.face)
        outwards = abs(f.normal[1]) >= abs(f.normal[0])  # the tool's +y points away from the Omni
        base = np.array(START["along" if outwards else "across"])
        if not outwards and f.normal[0] > 0:  # a face pushing rightwards starts left of the axis
            base[0] = -base[0]
        return base + rng.normal(0.0, 0.002, 2)


def generate_calibration(out: str | Path, *, seed: int = 0, tool: str = "finger",
                         trials: list[Trial] | None = None, travel: float = TRAVEL) -> Path:
    """Write a calibration recording into the folder ``out`` in the dataset format (meta.yaml, one
    CSV per trial, truth.yaml); returns the folder.

    Args:
        out: the folder; seed: the sensor noise and the operator's variation (deterministic for it).
        tool: the tool (``finger``, the scripted operator's tool).
        trials: the trials (default :func:`default_trials`); travel: how far [m] each moves the puck.
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError("seed", "a non-negative integer", repr(seed))
    if tool != "finger":
        raise InputError("tool", "'finger' (the scripted operator calibrates with tool 1)", repr(tool))
    if isinstance(travel, bool) or not isinstance(travel, int | float) or not 0.005 <= travel <= 0.05:
        raise InputError("travel", "a puck travel per trial in [0.005, 0.05] m", repr(travel))
    op = CalibrationOperator(tool=load_tool(tool), travel=float(travel))
    chosen = default_trials(op.tool) if trials is None else list(trials)
    if not chosen:
        raise InputError("trials", "at least one calibration trial", "none")
    for i, tr in enumerate(chosen):
        if not isinstance(tr, Trial) or tr.face not in op.tool.face_names or not abs(tr.angle) < np.radians(89):
            raise InputError(f"trials[{i}]", "a Trial with a face of the tool and |angle| < 89 degrees", repr(tr))
    noise = np.random.default_rng(seed)
    place = np.random.default_rng(seed + 7919)
    demos: list[Demonstration] = []
    truth: dict[str, dict] = {}
    skipped: list[int] = []
    for k, tr in enumerate(chosen):
        start = op.trial_start(tr, place)
        for attempt in range(5):
            op_seed = 1000 * seed + 10 * k + attempt
            try:
                ex, tru = op.run_trial(tr, start, op_seed)
                break
            except DemonstrationFailed:
                skipped.append(op_seed)
        else:
            raise InputError("seed", f"a seed for which the operator finishes trial {tr.name}", seed)
        demos.append(record(ex, tr.name, op.platform, noise))
        truth[tr.name] = tru
    meta = Meta(
        tool=tool, object_radius=OBJECT_RADIUS, rates=RATES,
        platform=platform_meta(op.platform),
        demonstrations=[f"{d.name}.csv" for d in demos],
        scene={"kind": "calibration", "travel": float(travel),
               "trials": [{"name": t.name, "face": t.face, "angle_deg": round(float(np.degrees(t.angle)), 6)}
                          for t in chosen]},
        generator={"program": "tooltransfer demos --calibration", "seed": seed, "skipped_operator_seeds": skipped,
                   "object_noise": OBJECT_NOISE, "joint_step": JOINT_STEP,
                   "tool_pose": "forward kinematics of the quantized joints"},
    )
    return write_dataset(out, meta, demos, truth)
