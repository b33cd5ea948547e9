"""DMP core benchmark: run with `make bench` (or `python benchmarks/bench_dmp.py [--quick]`).

1. Against movement_primitives' DMP (its default integrator) on 20 generated 2-D paths of 1,000
   samples, 50 basis functions per dimension: fit time, rollout time, reproduction RMSE.
2. Constrained fit (cone + hexagon + disc), 2x30 weights / 200 samples and 2x60 / 1,000 samples,
   one linearisation: our path (OSQP on the whitened coarse rows, then the exact dual active-set
   step with dense cutting planes; also the exact step alone) against OSQP, quadprog and clarabel
   on the plain condensed formulation through qpsolvers, with the true max violation on the dense
   grid (10x the constraint grid); also ours re-linearised until the path settles (the default,
   warm-started across linearisations). CPU-time medians of interleaved runs (the machine is
   shared), ratios to quadprog in the same run.
3. The dual active-set core: the same constrained fits with the compiled core (``_gi_core.c``) and
   with its NumPy fallback (``dmp/qp/_gi_numpy.py``, what an install without a C compiler runs),
   interleaved, CPU-time medians, with the largest relative difference of the objectives.
OPENBLAS_NUM_THREADS=1 is set.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import time

import numpy as np

from tooltransfer.dmp import DMP
from tooltransfer.dmp.exact import RESPONSE_CACHE
from tooltransfer.dmp.qp import native, solve_fit
from tooltransfer.problems.fit_cases import l_push_case, minimum_jerk


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
    """Median CPU time (``time.process_time`` around the whole ``solve_fit`` call, so the final
    dense-grid check is included for every formulation) over ``reps`` interleaved runs: each
    repetition runs every formulation once, so a change of machine load hits all of them alike.
    The ratio to quadprog (exact on its own rows, the reference peer) is taken per size."""
    print(f"\n== constrained fit (cone + hexagon + disc), CPU-time medians of {reps} interleaved runs ==")
    print(
        f"{'size':<14}{'formulation':<42}{'CPU ms':>8}{'wall ms':>9}{'max viol':>10}{'status':>12}"
        f"{'steps':>7}{'/quadprog':>10}"
    )
    forms = (
        ("ours: osqp seed + exact cutting planes", {"solver": "osqp", "strategy": "cutting_planes", "max_scp": 1}),
        ("ours, exact step alone (no seed)", {"strategy": "cutting_planes", "max_scp": 1, "seed_with_backend": False}),
        ("ours, re-linearised until settled", {"strategy": "cutting_planes"}),
        ("osqp condensed (full)", {"solver": "osqp", "strategy": "full", "max_scp": 1}),
        ("quadprog condensed (full)", {"solver": "quadprog", "strategy": "full", "max_scp": 1}),
        ("clarabel condensed (full)", {"solver": "clarabel", "strategy": "full", "max_scp": 1}),
    )
    targets = {200: 10e-3, 1000: 30e-3}
    for nb, ns in ((30, 200), (60, 1000)):
        case = l_push_case(nb, ns)
        cpu: dict[str, list[float]] = {label: [] for label, _ in forms}
        wall: dict[str, list[float]] = {label: [] for label, _ in forms}
        last = {}
        for _, kw in forms:
            solve_fit(case.problem, **kw)  # warm the grid caches
        for rep in range(reps):
            for label, kw in forms:
                slow = kw.get("solver") == "clarabel" or (kw.get("solver") == "osqp" and kw["strategy"] == "full")
                if rep and slow:
                    continue  # 0.1-30 s per run (OSQP at eps 1e-7): one run is enough
                c0 = time.process_time()
                r = solve_fit(case.problem, **kw)
                cpu[label].append(time.process_time() - c0)
                wall[label].append(r.solve_time)
                last[label] = r
        med = {label: float(np.median(v)) for label, v in cpu.items()}
        ref = med["quadprog condensed (full)"]
        for label, _ in forms:
            r = last[label]
            print(
                f"2x{nb}/{ns:<8}{label:<42}{1e3 * med[label]:8.2f}{1e3 * np.median(wall[label]):9.2f}"
                f"{r.max_violation:10.1e}{r.status:>12}{r.n_exact:7d}{med[label] / ref:10.2f}"
            )
        ours = med["ours: osqp seed + exact cutting planes"]
        ok = ours <= targets[ns] and ours <= ref
        print(
            f"  target (ours <= {1e3 * targets[ns]:.0f} ms and <= quadprog in the same run): "
            f"{'met' if ok else 'NOT met'} ({1e3 * ours:.2f} ms, {ours / ref:.2f} x quadprog)"
        )


def bench_cores(reps: int) -> None:
    """The constrained fit on the compiled core and on the NumPy core (the fallback without a
    compiler): CPU-time medians of ``reps`` interleaved runs of the whole ``solve_fit`` call."""
    print(f"\n== dual active-set core: compiled vs NumPy, CPU-time medians of {reps} interleaved runs ==")
    if native.compiled_path() is None:
        print("the compiled core is not built: nothing to compare")
        return
    print(f"{'size':<14}{'fit':<36}{'compiled ms':>12}{'NumPy ms':>10}{'NumPy/compiled':>16}{'steps':>7}"
          f"{'rel. obj. diff':>16}")
    forms = (
        ("osqp seed + exact, one linearisation", {"max_scp": 1}),
        ("exact step alone, one linearisation", {"max_scp": 1, "seed_with_backend": False}),
        ("re-linearised until settled (default)", {}),
    )
    for nb, ns in ((30, 200), (60, 1000)):
        case = l_push_case(nb, ns)
        for label, kw in forms:
            cpu: dict[str, list[float]] = {"compiled": [], "numpy": []}
            last = {}
            for which in cpu:  # warm the grid caches
                with native.using(which):
                    solve_fit(case.problem, **kw)
            for _ in range(reps):
                for which in cpu:
                    with native.using(which):
                        c0 = time.process_time()
                        last[which] = solve_fit(case.problem, **kw)
                        cpu[which].append(time.process_time() - c0)
            med = {k: float(np.median(v)) for k, v in cpu.items()}
            a, b = last["compiled"], last["numpy"]
            rel = abs(a.objective - b.objective) / abs(a.objective)
            print(f"2x{nb}/{ns:<8}{label:<36}{1e3 * med['compiled']:12.2f}{1e3 * med['numpy']:10.2f}"
                  f"{med['numpy'] / med['compiled']:16.2f}{b.n_exact:7d}{rel:16.1e}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer paths and repetitions")
    ap.add_argument("--constrained", action="store_true", help="only the constrained-fit parts")
    ap.add_argument("--cores", action="store_true", help="only the compiled vs NumPy core part")
    a = ap.parse_args()
    if not a.constrained and not a.cores:
        bench_vs_movement_primitives(8 if a.quick else 20, 3 if a.quick else 5)
    if not a.cores:
        bench_constrained(5 if a.quick else 9)
    bench_cores(5 if a.quick else 9)


if __name__ == "__main__":
    main()
