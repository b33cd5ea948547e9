"""Many executions at once: a process pool over independent simulations (MuJoCo releases nothing
to share between them, so processes scale with the cores; results equal the sequential ones)."""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tools.model import Tool
from tools.objects import Obstacle
from tools.omni.platform import OmniPlatform
from tools.sim.platform import Execution, Rates, SimPlatform


@dataclass(frozen=True)
class Job:
    """One execution: the puck's start ``object_xy`` (2,) [m], the arm's start ``q0`` (3,) [rad] and
    the joint path ``q`` (T, 3) [rad] over times ``t`` (T,) [s]."""

    object_xy: NDArray[np.float64]
    q0: NDArray[np.float64]
    t: NDArray[np.float64]
    q: NDArray[np.float64]


def _run(args: tuple[Tool, OmniPlatform, tuple[Obstacle, ...], Job, Rates]) -> Execution:
    tool, platform, obstacles, job, rates = args
    sim = SimPlatform(tool, platform, obstacles)
    sim.reset(job.object_xy, q0=job.q0)
    return sim.execute(job.t, job.q, rates=rates)


def execute_many(
    tool: Tool, jobs: Sequence[Job], *, platform: OmniPlatform | None = None, obstacles: Sequence[Obstacle] = (),
    rates: Rates | None = None, workers: int | None = None,
) -> list[Execution]:
    """Run ``jobs`` (each from a fresh reset) in ``workers`` processes (1: in this process); the
    recordings come back in the jobs' order."""
    plat = platform or OmniPlatform(a_t=tool.a_t)
    args = [(tool, plat, tuple(obstacles), j, rates or Rates()) for j in jobs]
    if workers == 1:
        return [_run(a) for a in args]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(_run, args))
