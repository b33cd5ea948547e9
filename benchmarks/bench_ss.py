"""SS switching benchmark, one command: `python benchmarks/bench_ss.py`. Medians (the machine is shared
and timings are noisy). Targets: ``opt`` switch with a reused solver at N = 40 for the
library's tools (convex pieces), shapely verification included, <= 15 ms; a capsule tool <= 3 ms;
``dmp`` switch <= 2 ms; IPOPT iteration counts and the failure rate over >= 200 random switches.
Wall and CPU (``time.process_time``) medians; a peer configuration is measured in the same run."""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import collections
import subprocess
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from tooltransfer.planner.learning.switch_dataset import dataset_switches, default_dataset
from tooltransfer.planner.planning.ss import (
    OptOptions,
    SwitchSkill,
    SwitchTask,
    learn_switch_skill,
    optimize,
    recombine,
)
from tooltransfer.planner.planning.ss.cases import FIG11, fig11_task, random_task
from tooltransfer.planner.planning.ss.switch_rows import Capsule
from tooltransfer.tools.library import load_tool


def _ms(x: list[float]) -> str:
    return f"median {1e3 * np.median(x):.1f} ms (p90 {1e3 * np.percentile(x, 90):.1f})"


def _kind(reason: str) -> str:
    if "contact pose" in reason:
        return "contact pose unreachable or overlapping"
    if "exact check" in reason:
        return "exact check after refinements"
    return reason.split(":")[0].replace("the NLP ", "NLP ")


def _timed(fn: Callable[..., Any], *args: Any, **kw: Any) -> tuple[Any, float, float]:
    """(result, wall [s], CPU [s]) of one call."""
    c0, w0 = time.process_time(), time.perf_counter()
    r = fn(*args, **kw)
    return r, time.perf_counter() - w0, time.process_time() - c0


def run_opt(skill: SwitchSkill, tasks: list[SwitchTask], label: str, **kw: Any) -> None:
    """The opt variant over ``tasks`` with a reused solver (each structure built once before)."""
    for t in tasks:
        optimize(skill, t, OptOptions(**kw))
    wall, cpu, solve, ver, its, status, starts = [], [], [], [], [], collections.Counter(), collections.Counter()
    for t in tasks:
        r, w, c = _timed(optimize, skill, t, OptOptions(**kw))
        status[r.status if r.ok else f"{r.status} ({_kind(r.reason)})"] += 1
        if r.ok:
            wall.append(w)
            cpu.append(c)
            solve.append(sum(a["solve_time"] for a in r.info["attempts"]))
            ver.append(sum(a.get("verify_time", 0.0) for a in r.info["attempts"]))
            its.append(r.info["iterations"])
            starts[f"{r.info['attempts'][0]['start']}, {len(r.info['attempts'])} attempt(s)"] += 1
    n = len(tasks)
    fails = n - status["solved"] - sum(v for k, v in status.items() if "contact pose" in k)
    print(f"opt {label} over {n} random switches (library tools, random faces and contact points, 30% with a disc "
          f"obstacle): whole switch wall {_ms(wall)}, CPU {_ms(cpu)}; NLP solve {_ms(solve)}; shapely check "
          f"{_ms(ver)}; IPOPT iterations median {np.median(its):.0f}, p90 {np.percentile(its, 90):.0f}, max "
          f"{max(its)}; failure rate (not solved although both contact poses are possible) {fails}/{n} "
          f"({100 * fails / n:.1f} %); outcomes {dict(status)}; solved from {dict(starts)}")


def main(n_random: int = 200, seed: int = 0) -> None:
    demos = dataset_switches(default_dataset(), ("upper", "left"))
    skill = learn_switch_skill(demos, virtual="arch", tool="finger")
    print(f"skill: {len(demos)} upper->left switches of the default dataset, virtual motion 'arch'")
    print(f"machine load (1, 5, 15 min): {os.getloadavg()} on {os.cpu_count()} CPUs (CPU times are less "
          "sensitive to it than wall times)")
    rng = np.random.default_rng(seed)
    tasks = [random_task(rng, obstacle_prob=0.3) for _ in range(n_random)]
    run_opt(skill, tasks, "(pieces, IPOPT, N = 40, defaults)")
    run_opt(skill, tasks, "(peer in the same run: vector separators, the default before)", separators="vector")
    run_opt(skill, tasks, "(angle separators)", separators="angle")
    run_opt(skill, tasks, "(peer in the same run: the dmp path as the only start, as before)", init="dmp")
    for name in FIG11:
        task = fig11_task(name)
        optimize(skill, task)
        tt, tc = [], []
        for _ in range(15):
            r, w, c = _timed(optimize, skill, task)
            tt.append(w)
            tc.append(c)
        d = recombine(skill, task, n_samples=40)
        print(f"{name} ({FIG11[name][0]}, {FIG11[name][1]} -> {FIG11[name][2]}): opt wall {_ms(tt)}, CPU {_ms(tc)}, "
              f"start {r.info['attempts'][0]['start']!r}, "
              f"{r.info['iterations']} iterations, penetration {1e3 * r.object_penetration:.4f} mm, clearance "
              f"{1e3 * r.object_clearance:.2f} mm; dmp penetration {1e3 * d.object_penetration:.2f} mm")
    finger = load_tool("finger")
    cap = Capsule.enclosing(finger)
    ctasks = [SwitchTask(finger, "upper", "left", 0.16 * np.array([np.cos(a), np.sin(a)]))
              for a in np.pi / 2 + rng.uniform(-0.4, 0.4, 40)]
    for solver in ("sqp", "ipopt"):
        for t in ctasks[:1]:
            optimize(skill, t, OptOptions(model="capsule", solver=solver))
        tot, cpu, its, ok = [], [], [], 0
        for t in ctasks:
            r, w, c = _timed(optimize, skill, t, OptOptions(model="capsule", solver=solver))
            ok += r.ok
            if r.ok:
                tot.append(w)
                cpu.append(c)
                its.append(r.info["iterations"])
        print(f"opt capsule model of tool 1 (radius {1e3 * cap.radius:.2f} mm), {solver}, N = 40, 40 switches: "
              f"wall {_ms(tot)}, CPU {_ms(cpu)}, iterations median {np.median(its):.0f}, solved {ok}/40")
    res: dict[str, tuple[list[float], list[float]]] = {}
    for label, kw in (("with the shapely report", {}), ("path only", {"measured": False}),
                      ("with the shapely report, peer: DMP.fit and rollout on every call", {"fast": False})):
        wall, cpu = [], []
        for t in tasks:
            _, w, c = _timed(recombine, skill, t, n_samples=40, **kw)
            wall.append(w)
            cpu.append(c)
        res[label] = (wall, cpu)
    print(f"dmp switch (40 samples) over {n_random} random switches: "
          + "; ".join(f"{k}: wall {_ms(w)}, CPU {_ms(c)}" for k, (w, c) in res.items()))

_FRESH = """
import time
t0 = time.perf_counter()
import casadi as ca
from tooltransfer.planner.planning.ss.bodies import all_bodies
from tooltransfer.planner.planning.ss.cases import fig11_task
from tooltransfer.planner.planning.ss.nlp import build_nlp
t1 = time.perf_counter()
task = fig11_task("fig11a")
bodies = all_bodies(task.shape, task.obstacles)
a = build_nlp(task.tool, 40, task.omni, bodies)
b = build_nlp(task.tool, 40, task.omni, bodies, reach=(False, True, False))
blob = a.solver.serialize()
t2 = time.perf_counter()
ca.Function.deserialize(blob)
t3 = time.perf_counter()
print(f"{1e3 * (t1 - t0):.0f} {1e3 * a.build_time:.0f} {1e3 * b.build_time:.0f} {1e3 * (t3 - t2):.0f} {len(blob)}")
"""


def fresh_builds(runs: int = 3) -> None:
    """Solver build cost in fresh processes (Fig. 11a, N = 40): the first structure (it also loads the
    IPOPT plugin), a second one, and loading the first from CasADi's serialization instead."""
    rows = []
    for _ in range(runs):
        out = subprocess.run([sys.executable, "-c", _FRESH], capture_output=True, text=True, check=True)
        rows.append([float(v) for v in out.stdout.split()])
    imp, first, second, load, size = np.median(np.array(rows), axis=0)
    print(f"fresh process, Fig. 11a structure, N = 40 (medians of {runs}): import {imp:.0f} ms; first build "
          f"{first:.0f} ms (with the IPOPT plugin load), second structure {second:.0f} ms; deserializing the "
          f"built solver instead {load:.0f} ms ({size / 1e6:.1f} MB), {second / load:.1f}x faster than a build of a "
          "second structure")


if __name__ == "__main__":
    fresh_builds()
    main()
