"""DMP core benchmark: run with `make bench` (or `python benchmarks/bench_dmp.py [--quick]`).

1. Against movement_primitives' DMP (its default integrator) on 20 generated 2-D paths of 1,000
   samples, 50 basis functions per dimension: fit time, rollout time, reproduction RMSE.
2. Constrained fit (cone + hexagon + disc), 2x30 weights / 200 samples and 2x60 / 1,000 samples,
   one linearisation: our cutting-plane formulation with the exact dual active-set step (alone and
   seeded by OSQP) against OSQP, quadprog and clarabel on the plain condensed formulation through
   qpsolvers, with the true max violation on the dense grid (10x the constraint grid).
Medians of several runs; ratios are measured in the same run. OPENBLAS_NUM_THREADS=1 is set.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import time

import numpy as np

from dmp import DMP
from dmp.exact import RESPONSE_CACHE
from dmp.qp import solve_fit
from problems.fit_cases import l_push_case, minimum_jerk


def generated_paths(n: int, samples: int = 1000) -> list[tuple[np.ndarray, np.ndarray, str]]:
    rng = np.random.default_rng(0)
    out = []
    for i in range(n):
        kind = ["pushes", "L", "spiral", "loop_coord"][i % 4]
        t = np.linspace(0, rng.uniform(2, 6), samples)
        s = np.linspace(0, 1, samples)
        if kind == "pushes":
            pts = np.cumsum(rng.uniform(-0.05, 0.05, (4, 2)), axis=0)
            segs = np.array_split(np.arange(samples), 3)
            x = np.vstack([minimum_jerk(pts[j], pts[j + 1], len(seg)) for j, seg in enumerate(segs)])
        elif kind == "L":
            a = rng.uniform(0.05, 0.12, 2)
            n1 = samples // 2
            x = np.vstack(
                [minimum_jerk(np.zeros(2), [0, a[0]], n1), minimum_jerk([0, a[0]], [-a[1], a[0]], samples - n1)]
            )
        elif kind == "spiral":
            r = 0.02 + 0.06 * s
            th = 3 * np.pi * (10 * s**3 - 15 * s**4 + 6 * s**5)
            x = np.stack([r * np.cos(th), r * np.sin(th)], 1)
        else:  # start equals goal in the x coordinate
            x = np.stack([0.05 * np.sin(np.pi * s), 0.1 * s], 1)
        out.append((t, x, kind))
    return out


def median_time(fn, reps: int) -> float:
    ts = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def bench_vs_movement_primitives(n_paths: int, reps: int) -> None:
    from movement_primitives.dmp import DMP as MPDMP

    print(f"\n== DMP vs movement_primitives: {n_paths} paths x 1000 samples, 50 basis/dim, medians of {reps} ==")
    print(
        f"{'path':<11}{'fit mp':>9}{'fit ours':>9}{'roll mp':>10}{'roll ours':>10}{'cold':>8}"
        f"{'RMSE mp[m]':>12}{'RMSE ours':>11}{'RMSE traj':>11}"
    )
    fit_r, roll_r, wins = [], [], 0
    for t, x, kind in generated_paths(n_paths):
        dt = t[1] - t[0]
        mp = MPDMP(2, execution_time=t[-1], dt=dt, n_weights_per_dim=50)
        f_mp = median_time(lambda: mp.imitate(t, x), reps)
        v0 = np.gradient(x, t, axis=0)[0]  # paths may start moving: both reproduce with it
        mp.configure(start_y=x[0], start_yd=v0, goal_y=x[-1])
        r_mp = median_time(lambda: mp.open_loop(), max(1, reps // 2))
        y_mp = mp.open_loop()[1]
        ours = DMP(2, n_basis=50)
        f_ours = median_time(lambda: ours.fit(t, x), reps)
        RESPONSE_CACHE.clear()
        t0 = time.perf_counter()
        ours.rollout(t, x0=x[0], g=x[-1], v0=v0)
        cold = time.perf_counter() - t0
        r_ours = median_time(lambda: ours.rollout(t, x0=x[0], g=x[-1], v0=v0), reps)
        y = ours.rollout(t, x0=x[0], g=x[-1], v0=v0).x
        y_tr = DMP(2, n_basis=50).fit(t, x, method="trajectory").rollout(t, x0=x[0], g=x[-1], v0=v0).x
        m = min(len(y_mp), len(x))
        rm_mp = float(np.sqrt(np.mean(np.sum((y_mp[:m] - x[:m]) ** 2, 1))))
        rm = float(np.sqrt(np.mean(np.sum((y - x) ** 2, 1))))
        rm_tr = float(np.sqrt(np.mean(np.sum((y_tr - x) ** 2, 1))))
        wins += min(rm, rm_tr) < rm_mp
        fit_r.append(f_mp / f_ours)
        roll_r.append(r_mp / r_ours)
        print(
            f"{kind:<11}{1e3 * f_mp:8.2f}ms{1e3 * f_ours:7.2f}ms{1e3 * r_mp:8.1f}ms{1e3 * r_ours:8.3f}ms"
            f"{1e3 * cold:6.1f}ms{rm_mp:12.2e}{rm:11.2e}{rm_tr:11.2e}"
        )
    print(
        f"median speed-up: fit {np.median(fit_r):.1f}x, rollout (cached grid) {np.median(roll_r):.0f}x; "
        f"lower RMSE than movement_primitives on {wins}/{n_paths} paths"
    )


def bench_constrained(reps: int) -> None:
    print(f"\n== constrained fit, one linearisation, medians of {reps} ==")
    print(f"{'size':<14}{'formulation':<32}{'median ms':>10}{'max viol':>10}{'status':>12}")
    for nb, ns in ((30, 200), (60, 1000)):
        res = {}
        for label, solver, strat, seed in (
            ("ours: cutting planes, exact", "osqp", "cutting_planes", False),
            ("ours, seeded by osqp", "osqp", "cutting_planes", True),
            ("osqp condensed (full)", "osqp", "full", False),
            ("quadprog condensed (full)", "quadprog", "full", False),
            ("clarabel condensed (full)", "clarabel", "full", False),
        ):
            case = l_push_case(nb, ns)
            kw = {"solver": solver, "strategy": strat, "max_scp": 1, "seed_with_backend": seed}
            solve_fit(case.problem, **kw)  # warm the grid caches
            times, r = [], None
            slow = solver == "clarabel" or (solver == "osqp" and strat == "full")
            for _ in range(reps if not slow or ns == 200 else 1):
                r = solve_fit(case.problem, **kw)
                times.append(r.solve_time)
            res[label] = float(np.median(times))
            print(f"2x{nb}/{ns:<8}{label:<32}{1e3 * res[label]:10.1f}{r.max_violation:10.1e}{r.status:>12}")
        ours = res["ours: cutting planes, exact"]
        print(
            "  ratios to ours: "
            + ", ".join(f"{k} {v / ours:.2f}" for k, v in res.items() if not k.startswith("ours: "))
        )


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer paths and repetitions")
    a = ap.parse_args()
    bench_vs_movement_primitives(8 if a.quick else 20, 3 if a.quick else 5)
    bench_constrained(3 if a.quick else 7)


if __name__ == "__main__":
    main()
