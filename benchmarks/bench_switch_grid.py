"""Switches the planner can make, before and after the ``grid`` fallback, one command::

    python benchmarks/bench_switch_grid.py [--tasks 40] [--per-task 5] [--seed 20261207]

Switches drawn at random on tasks of the verdict benchmark's batch (``problems/batch/verdicts_200.yaml``): the
puck anywhere the Omni reaches (its waist angle and reach drawn uniformly in the joints' box, the puck clear of
the obstacles), two different faces, each contact at a random place of its range, both contact poses within the
Omni's joints and clear of the obstacles (``test_verdicts.contact_pose``). Each switch goes to

- ``opt`` (the CasADi NLP near the SS skill's path, local), then the ``arch`` reference where it finds none:
  the chain before this benchmark's change (the peer);
- the ``grid`` search over every placement of the tool (:mod:`tooltransfer.planner.planning.ss.grid_variant`),
  where both found none: the chain now (``SS_VARIANTS["opt"]``);
- for a switch no planner made, the brute-force grid of ``tests/test_switch_space.py`` (the tool's outline
  placed with shapely on waist angles and reaches 0.6 mm apart, shrunk by the most a point moves between
  neighbours): two contact poses in different pieces of its free placements have no switch at all.

Prints the rates (with Wilson intervals), the reasons, and the CPU time per call of each planner (medians, p90).
Single-threaded BLAS. Exit code 0 (a measurement).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import math
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import shapely

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests")]

from test_switch_space import placement_pieces  # noqa: E402
from test_verdicts import contact_pose, generated  # noqa: E402

from tooltransfer.planner.apps.batch.stats import wilson  # noqa: E402
from tooltransfer.planner.planning.setting import setting_from_task, task_skills  # noqa: E402
from tooltransfer.planner.planning.ss.grid_variant import grid_planner, placement_of  # noqa: E402
from tooltransfer.planner.planning.switches import arch_planner, opt_planner  # noqa: E402
from tooltransfer.tools.objects import Disc  # noqa: E402
from tooltransfer.tools.omni.reach import reach_sector  # noqa: E402
from tooltransfer.tools.pose import Pose2D  # noqa: E402


def _cpu(fn, *args):
    c0 = time.process_time()
    out = fn(*args)
    return out, time.process_time() - c0


def _separated(setting, centre: np.ndarray, poses: list[np.ndarray]) -> bool:
    """The brute-force grid puts the two contact poses in different pieces of the free placements."""
    sec = reach_sector(setting.platform)
    pieces = placement_pieces(setting, centre, [tuple(placement_of(sec, p)) for p in poses])
    return not (pieces[0] & pieces[1])


def _switches(task, setting, rng: np.random.Generator, n: int) -> list[tuple[np.ndarray, str, np.ndarray, str,
                                                                              np.ndarray]]:
    """Up to ``n`` random switches of ``task`` (module docstring), 200 draws at most."""
    from tooltransfer.planner.planning.ss.verify import pose_depth_and_gap

    sec = reach_sector(setting.platform)
    faces = setting.tool.faces
    out = []
    for _ in range(200):
        if len(out) == n:
            break
        centre = sec.point(rng.uniform(*sec.q1_range), rng.uniform(*sec.u_range))
        if any(shapely.distance(shapely.Point(centre), o.polygon() if isinstance(o, Disc) else o) < setting.radius
               for o in setting.obstacles):
            continue
        i, j = rng.choice(len(faces), 2, replace=False)
        poses = []
        for f in (faces[i], faces[j]):
            got = contact_pose(sec, f, centre, setting.radius, float(rng.uniform(*f.contact_range)))
            if got is None:
                break
            a, u, q1 = got
            xy = sec.point(q1, u)
            pose = np.array([xy[0], xy[1], a - math.pi / 2])
            if any(pose_depth_and_gap(setting.tool, Pose2D(*pose), o)[0] > 0.0 for o in setting.obstacles):
                break
            poses.append(pose)
        if len(poses) == 2:
            out.append((centre, faces[i].name, poses[0], faces[j].name, poses[1]))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tasks", type=int, default=40, help="tasks of the batch, the first ones (default 40)")
    ap.add_argument("--per-task", type=int, default=5, help="switches drawn per task (default 5)")
    ap.add_argument("--seed", type=int, default=20261207, help="the draws' seed")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    tally: Counter[str] = Counter()
    times: dict[str, list[float]] = {"opt": [], "arch": [], "grid": []}
    why: Counter[str] = Counter()
    n = 0
    for k in range(args.tasks):
        task_id = f"verd200-{k:05d}"
        task = generated("verdicts_200.yaml", task_id)
        skills = task_skills(task)
        setting = setting_from_task(task, skills)
        opt = opt_planner(skills.ss, setting, task.ss.clearance, task.ss.n_knots)
        arch, grid = arch_planner(setting, task.ss.clearance), grid_planner(setting, task.ss.clearance)
        for sw in _switches(task, setting, rng, args.per_task):
            n += 1
            made, t = _cpu(opt, *sw)
            times["opt"].append(t)
            if made.ok:
                tally["opt"] += 1
                continue
            made, t = _cpu(arch, *sw)
            times["arch"].append(t)
            if made.ok:
                tally["arch (opt found none)"] += 1
                continue
            made, t = _cpu(grid, *sw)
            times["grid"].append(t)
            if made.ok:
                tally["grid (opt and arch found none)"] += 1
                print(f"  {task_id}: {sw[1]} -> {sw[3]} at {np.round(sw[0] * 1e3, 1).tolist()} mm: grid, "
                      f"{1e3 * made.object_clearance:.2f} mm from the puck", flush=True)
                continue
            sep = _separated(setting, sw[0], [sw[2], sw[4]])
            tally["none; brute force separates the poses" if sep else "none; brute force does NOT separate them"] += 1
            why[made.reason.split(": ", 1)[-1][:90]] += 1
            print(f"  {task_id}: {sw[1]} -> {sw[3]} at {np.round(sw[0] * 1e3, 1).tolist()} mm: none "
                  f"({'separated' if sep else 'not separated'} by brute force)", flush=True)
    before = tally["opt"] + tally["arch (opt found none)"]
    after = before + tally["grid (opt and arch found none)"]
    print(f"\n{n} switches on {args.tasks} tasks (seed {args.seed})")
    if n == 0:
        print("  none drawn: nothing to measure")
        return 0
    for label, k in (("opt -> arch (before)", before), ("opt -> arch -> grid (now)", after)):
        lo, hi = wilson(k, n)
        print(f"  {label:28s} {k:4d} / {n} = {100 * k / n:5.1f} % (Wilson 95 %: {100 * lo:.1f}-{100 * hi:.1f} %)")
    for label, k in sorted(tally.items()):
        print(f"    {label}: {k}")
    for reason, k in why.most_common():
        print(f"    grid's reason x{k}: {reason}")
    for name, ts in times.items():
        if ts:
            print(f"  CPU per call, {name:4s} ({len(ts)} calls): median {1e3 * np.median(ts):.0f} ms, "
                  f"p90 {1e3 * np.percentile(ts, 90):.0f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
