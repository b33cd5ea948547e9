"""Simulated platform benchmark: run with `python benchmarks/bench_sim.py` (or `make bench-sim`).

1. Wall time of executing a 10 s plan at a 1 ms step (10 000 physics steps): a push with tool 1's
   upper face along a tool path through the Omni's inverse kinematics, recorded at 30 Hz (object)
   and 200 Hz (tool); median of several runs, and the real-time factor (target: at least 10x,
   i.e. at most 1 s of wall time). The model is built once (its time is printed apart).
2. Batch throughput: 8 such plans (pucks at different places) one after another on one
   :class:`SimPlatform`, then through :func:`tooltransfer.tools.sim.execute_many` on 1 and 2 threads
   (``mujoco.rollout``), in simulated seconds per wall second; the results are checked equal.

Single-threaded BLAS (``OPENBLAS_NUM_THREADS=1``); the machine is shared, so figures vary by some
percent from run to run.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time
from collections.abc import Callable

import numpy as np

from tooltransfer.tools import contact_on_platform, load_tool
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.sim import Job, SimPlatform, execute_many
from tooltransfer.tools.sim.reference import tool_path_joints

DURATION = 10.0
REPEATS = 5


def push_plan(plat: OmniPlatform, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 10 s push: puck start (2,) [m], times (T,) [s], tool path (T, 2) [m] (70 mm forward)."""
    tool = load_tool("finger")
    obj = np.array([offset, 0.14])
    pose = contact_on_platform(tool, "upper", obj, np.pi / 2, plat).contact.pose
    start = np.array([pose.x, pose.y - 0.01])
    t = np.linspace(0.0, DURATION, 1001)
    s = t / DURATION
    return obj, t, start + (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None] * np.array([0.0, 0.07])


def median_time(fn: Callable[[], object], repeats: int = REPEATS) -> tuple[float, object]:
    out, times = None, []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main() -> None:
    tool = load_tool("finger")
    t0 = time.perf_counter()
    sim = SimPlatform(tool)
    build = time.perf_counter() - t0
    plat = sim.platform
    obj, t, path = push_plan(plat)

    def one() -> float:
        sim.reset(obj, tool_xy=path[0])
        ex = sim.execute_tool_path(t, path)
        return float(ex.object_xy[-1, 1] - obj[1])

    one()  # warm-up
    wall, travel = median_time(one)
    print(f"model build: {1e3 * build:.0f} ms (once per platform)")
    print(f"10 s plan at 1 ms ({round(DURATION / sim.config.timestep)} steps), IK + physics + recording: "
          f"median wall {wall:.3f} s over {REPEATS} runs = {DURATION / wall:.1f}x real time "
          f"(target >= 10x); puck travel {1e3 * travel:.1f} mm")

    offsets = np.linspace(-0.03, 0.03, 8)
    plans = [push_plan(plat, o) for o in offsets]
    jobs = [Job(o, tt, tool_path_joints(plat, p, tt)) for o, tt, p in plans]

    def sequential() -> list:
        outs = []
        for job in jobs:
            sim.reset(job.object_xy, q0=job.q[0])
            outs.append(sim.execute(job.t, job.q))
        return outs

    simulated = len(jobs) * DURATION
    w_seq, seq = median_time(sequential, 3)
    print(f"8 plans of 10 s one after another on one SimPlatform: {w_seq:.2f} s, "
          f"{simulated / w_seq:.0f} simulated s per wall s")
    for threads in (1, 2):
        w, par = median_time(lambda th=threads: execute_many(tool, jobs, platform=plat, threads=th), 3)
        same = all(np.array_equal(a.object_xy, b.object_xy) and np.array_equal(a.joints, b.joints)
                   for a, b in zip(seq, par, strict=True))  # type: ignore[arg-type]
        print(f"8 plans of 10 s through execute_many, {threads} thread(s): {w:.2f} s, "
              f"{simulated / w:.0f} simulated s per wall s, speed-up {w_seq / w:.2f}x; "
              f"equal to the sequential results: {same}")


if __name__ == "__main__":
    main()
