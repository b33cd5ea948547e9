"""Generate a demonstration dataset: the scripted operator on the simulated platform, recorded as
sensors give it, written in the dataset format (:mod:`tooltransfer.problems.dataset`).

Sensors:

* the object track as a depth camera gives it: 30 Hz, Gaussian noise of ``OBJECT_NOISE`` = 1.5 mm
  per axis (the paper's Kinect-class camera; docs/design.md section 9 says 1-2 mm);
* the joints as the Omni's encoders give them: 100 Hz, quantized to ``JOINT_STEP`` = 2e-4 rad (the
  device's nominal position resolution, about 0.055 mm, over its reach of about 0.27 m); the tool
  pose is what the device reports, the forward kinematics of those quantized joints (so it also
  carries the small difference between the kinematic model and the simulated arm, about 0.04 mm).

Deterministic for a seed: the sensor noise comes from ``numpy.random.default_rng(seed)`` and the
operator of demonstration candidate ``k`` (k = 0, 1, ...) from seed ``1000 * seed + k``; candidates
where the operator cannot finish, or where the puck does not end in the target square, are skipped
(a person would do them again) and listed in ``meta.yaml``, until ``n`` demonstrations are kept.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.operator.operator import DemonstrationFailed, ScriptedOperator
from tooltransfer.problems.dataset import Demonstration, Meta, PlatformMeta, Rates, write_dataset
from tooltransfer.problems.demo_scene import DEMO_SCENE
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.objects import OBJECT_RADIUS
from tooltransfer.tools.omni.ik import table_pose
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim import Execution

OBJECT_NOISE = 0.0015
"""Camera noise [m], standard deviation per axis."""
JOINT_STEP = 2e-4
"""Encoder quantization step [rad]."""
RATES = Rates(object_hz=30.0, tool_hz=100.0)


def platform_meta(platform: OmniPlatform) -> PlatformMeta:
    """The Omni's placement as a dataset's ``meta.yaml`` records it."""
    return PlatformMeta(a_t=platform.a_t, base_xy=tuple(platform.base_xy), base_yaw=platform.base_yaw,
                        table_height=platform.table_height)


def record(ex: Execution, name: str, platform: OmniPlatform, rng: np.random.Generator) -> Demonstration:
    """What the sensors give of one execution recorded at every 1 ms physics step: the camera's
    samples on its own 30 Hz clock with noise, the encoders' on their 100 Hz clock quantized, and
    the tool pose by forward kinematics of the quantized joints."""
    ms_o = np.round(ex.t_object * 1000.0).astype(np.int64)
    ms_t = np.round(ex.t_tool * 1000.0).astype(np.int64)
    cam = np.isin(ms_o, np.round(np.arange(1, ms_o[-1] * RATES.object_hz / 1000.0 + 1) * 1000.0 / RATES.object_hz))
    enc = ms_t % round(1000.0 / RATES.tool_hz) == 0
    obj = ex.object_xy[cam] + rng.normal(0.0, OBJECT_NOISE, (int(cam.sum()), 2))
    joints = np.round(ex.joints[enc] / JOINT_STEP) * JOINT_STEP
    pose = np.array([table_pose(platform, q) for q in joints]).reshape(-1, 3)
    return Demonstration(name, ms_o[cam] / 1000.0, obj, ms_t[enc] / 1000.0, pose, joints)


def generate_demonstrations(out: str | Path, *, n: int = 8, seed: int = 0, tool: str = "finger") -> Path:
    """Write ``n`` demonstrations with ``tool`` into the folder ``out`` (meta.yaml, one CSV per
    demonstration, truth.yaml with the operator's ground truth); returns the folder."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise InputError("n", "a positive number of demonstrations", repr(n))
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError("seed", "a non-negative integer", repr(seed))
    if tool != "finger":
        raise InputError("tool", "'finger' (the scripted operator demonstrates with tool 1)", repr(tool))
    op = ScriptedOperator(tool=load_tool(tool))
    rng = np.random.default_rng(seed)
    demos: list[Demonstration] = []
    truth: dict[str, dict] = {}
    skipped: list[int] = []
    for k in range(4 * n + 10):
        if len(demos) == n:
            break
        op_seed = 1000 * seed + k
        try:
            ex, tr = op.demonstrate(op_seed)
        except DemonstrationFailed:
            skipped.append(op_seed)
            continue
        if not DEMO_SCENE.in_target(ex.object_xy[-1]):
            skipped.append(op_seed)
            continue
        name = f"demo_{len(demos):02d}"
        demos.append(record(ex, name, op.platform, rng))
        truth[name] = {
            "operator_seed": op_seed,
            "reached_target": True,
            "final_object_xy": [round(float(v), 6) for v in ex.object_xy[-1]],
            "pushes": [{"face": f, "t_start": round(a, 6), "t_end": round(b, 6)} for f, a, b in tr.pushes],
            "switches": [{"from": a, "to": b, "t_start": round(s, 6), "t_end": round(e, 6),
                          "object_xy": [round(c[0], 6), round(c[1], 6)]}
                         for (a, b, s, e), c in zip(tr.switches, tr.corners, strict=True)],
        }
    if len(demos) < n:
        raise InputError("seed", "a seed for which the operator finishes enough demonstrations", seed)
    meta = Meta(
        tool=tool, object_radius=OBJECT_RADIUS, rates=RATES,
        platform=platform_meta(op.platform),
        demonstrations=[f"{d.name}.csv" for d in demos],
        scene=DEMO_SCENE.to_dict(),
        generator={"program": "tooltransfer demos", "seed": seed, "skipped_operator_seeds": skipped,
                   "object_noise": OBJECT_NOISE, "joint_step": JOINT_STEP,
                   "tool_pose": "forward kinematics of the quantized joints"},
    )
    return write_dataset(out, meta, demos, truth)
