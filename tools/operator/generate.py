"""Generate a demonstration dataset: the scripted operator on the simulated platform, recorded as
sensors give it, written in the dataset format (:mod:`problems.dataset`).

Sensors: the object track as a depth camera gives it (30 Hz, Gaussian noise of 1.5 mm per axis),
the tool pose and joints as the Omni's encoders give them (100 Hz; joints quantized to 1e-4 rad,
tool position noise 0.05 mm, heading 2e-4 rad). Deterministic for a seed: demonstration ``i`` uses
operator seed ``1000 * seed + k`` for k = 0, 1, ... (seeds where the operator cannot finish, or
where the puck does not end in the target square, are skipped in order and listed in
``meta.yaml``), until ``n`` demonstrations are kept.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dmp.errors import InputError
from problems.dataset import Demonstration, Meta, PlatformMeta, Rates, write_dataset
from tools.library import load_tool
from tools.objects import OBJECT_RADIUS
from tools.operator.operator import DemonstrationFailed, ScriptedOperator
from tools.operator.scene import DEMO_SCENE

OBJECT_NOISE, TOOL_NOISE, YAW_NOISE, JOINT_STEP = 0.0015, 5e-5, 2e-4, 1e-4


def generate_demonstrations(out: str | Path, *, n: int = 8, seed: int = 0, tool: str = "finger") -> Path:
    """Write ``n`` demonstrations with ``tool`` into the folder ``out``; returns the folder."""
    if not isinstance(n, int) or n < 1:
        raise InputError("n", "a positive number of demonstrations", repr(n))
    if tool != "finger":
        raise InputError("tool", "'finger' (the scripted operator demonstrates with tool 1)", repr(tool))
    t1 = load_tool(tool)
    op = ScriptedOperator(tool=t1)
    rng = np.random.default_rng(seed)
    demos, names, truth, skipped = [], [], {}, []
    k = 0
    while len(demos) < n:
        op_seed = 1000 * seed + k
        k += 1
        if k > 4 * n + 10:
            raise InputError("seed", "a seed for which the operator finishes enough demonstrations", seed)
        try:
            ex, tr = op.demonstrate(op_seed)
        except DemonstrationFailed:
            skipped.append(op_seed)
            continue
        if not DEMO_SCENE.in_target(ex.object_xy[-1]):  # a human would redo it: so does the script
            skipped.append(op_seed)
            continue
        name = f"demo_{len(demos):02d}.csv"
        obj = ex.object_xy + rng.normal(0.0, OBJECT_NOISE, ex.object_xy.shape)
        pose = ex.tool_pose + np.column_stack([rng.normal(0.0, TOOL_NOISE, (len(ex.t_tool), 2)),
                                               rng.normal(0.0, YAW_NOISE, len(ex.t_tool))])
        joints = np.round(ex.joints / JOINT_STEP) * JOINT_STEP
        demos.append(Demonstration(name[:-4], ex.t_object, obj, ex.t_tool, pose, joints))
        names.append(name)
        truth[name[:-4]] = {
            "operator_seed": op_seed,
            "reached_target": DEMO_SCENE.in_target(ex.object_xy[-1]),
            "final_object_xy": [round(float(v), 6) for v in ex.object_xy[-1]],
            "pushes": [{"face": f, "t_start": round(a, 6), "t_end": round(b, 6)} for f, a, b in tr.pushes],
            "switches": [{"from": a, "to": b, "t_start": round(s, 6), "t_end": round(e, 6)}
                         for a, b, s, e in tr.switches],
        }
    plat = op.platform
    meta = Meta(
        tool=tool, object_radius=OBJECT_RADIUS, rates=Rates(object_hz=30.0, tool_hz=100.0),
        platform=PlatformMeta(a_t=plat.a_t, base_xy=plat.base_xy, base_yaw=plat.base_yaw,
                              table_height=plat.table_height),
        demonstrations=names,
        scene={"corners": DEMO_SCENE.corners.tolist(), "faces": list(DEMO_SCENE.faces),
               "obstacle": {"centre": DEMO_SCENE.obstacle.centre.tolist(), "radius": DEMO_SCENE.obstacle.radius},
               "target_half": DEMO_SCENE.target_half},
        generator={"seed": seed, "skipped_operator_seeds": skipped, "object_noise": OBJECT_NOISE,
                   "tool_noise": TOOL_NOISE, "yaw_noise": YAW_NOISE, "joint_step": JOINT_STEP},
    )
    return write_dataset(out, meta, demos, truth)
