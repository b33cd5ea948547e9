"""Simulated platform benchmark: run with `python benchmarks/bench_sim.py` (or `make bench-sim`).

Wall time of executing a 10 s tool path (a push with tool 1) at a 1 ms step, median of several
runs, and the real-time factor (target: at least 10x faster than real time); then the throughput
of many executions through a process pool against running them one after another.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from tools import contact_on_platform, load_tool
from tools.sim import SimPlatform


def run_push(offset: float = 0.0) -> float:
    """Execute a 10 s push; returns the puck's forward travel [m]."""
    tool = load_tool("finger")
    sim = SimPlatform(tool)
    obj = np.array([offset, 0.14])
    pose = contact_on_platform(tool, "upper", obj, np.pi / 2, sim.platform).contact.pose
    start = np.array([pose.x, pose.y - 0.01])
    sim.reset(obj, tool_xy=start)
    t = np.linspace(0.0, 10.0, 1001)
    s = t / 10.0
    path = start + (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None] * np.array([0.0, 0.07])
    ex = sim.execute_tool_path(t, path)
    return float(ex.object_xy[-1, 1] - obj[1])


def main() -> None:
    run_push()
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        travel = run_push()
        times.append(time.perf_counter() - t0)
    med = float(np.median(times))
    print(f"10 s plan at 1 ms: median wall {med:.3f} s (model build included), {10.0 / med:.1f}x real time; "
          f"puck travel {1e3 * travel:.1f} mm")
    offsets = np.linspace(-0.03, 0.03, 8)
    t0 = time.perf_counter()
    seq = [run_push(o) for o in offsets]
    t_seq = time.perf_counter() - t0
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=2) as pool:
        par = list(pool.map(run_push, offsets))
    t_par = time.perf_counter() - t0
    assert np.allclose(seq, par)  # the same results either way
    print(f"8 executions: sequential {t_seq:.2f} s, process pool (2 workers) {t_par:.2f} s, "
          f"speed-up {t_seq / t_par:.2f}x, {8 * 10.0 / t_par:.0f} simulated s per wall s")


if __name__ == "__main__":
    main()
