"""OE condensing benchmark on the paper's transfer case (tool 1's demos -> tool 2), one command:
`python benchmarks/bench_oe.py`. Medians of several runs of the whole OE step (the ``qp`` variant
including its push-sequence search; the ``mapping`` variant), the number of QPs (sequential-convex
solves) and the time per QP, in CPU time (the machine is shared). Targets: qp <= 300 ms (with the
push mechanics), each QP <= 20 ms, mapping <= 50 ms. The scene: the
paper's puck with the platform's nominal mechanics (mu 0.8, c 0.59)."""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import time

import numpy as np

from tooltransfer.planner.planning.oe import condense_qp
from tooltransfer.planner.planning.oe.mapping_variant import condense_mapping
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.ss.paper_cases import transfer_case
from tooltransfer.tools.objects import DiscObject


def main(reps: int = 7) -> None:
    case = transfer_case()
    setting = Setting(case.tool, case.platform, DiscObject(0.0175), obstacles=case.obstacles)
    args = (case.t, case.x, setting, case.target)
    condense_qp(*args)
    condense_mapping(*args)
    tq, tm, plan = [], [], None
    for _ in range(reps):
        t0 = time.process_time()
        plan = condense_qp(*args)
        tq.append(time.process_time() - t0)
        t0 = time.process_time()
        condense_mapping(*args)
        tm.append(time.process_time() - t0)
    m = plan.metrics
    print(f"qp variant: median {1e3 * np.median(tq):.0f} ms for the whole OE step ({int(m['n_qp'])} QPs, "
          f"{len(plan.candidates)} sequences scored), per QP median {1e3 * m['qp_time_median']:.1f} ms, "
          f"max {1e3 * m['qp_time_max']:.1f} ms; pushes {plan.faces}")
    print(f"mapping variant: median {1e3 * np.median(tm):.1f} ms")


if __name__ == "__main__":
    main()
