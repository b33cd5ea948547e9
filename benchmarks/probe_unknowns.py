"""How near each unknown's target a search under the planner's own rules comes, the contact's rolling included.

Run after the verdict benchmark (``python benchmarks/bench_verdicts.py --json RESULTS``)::

    python benchmarks/probe_unknowns.py RESULTS.json [--budget 60000] [--workers 2] [--step 0.003] [--room 0.00025]
        [--span 0.0005] [--windows 0] [--share 0.8] [--directions 9] [--backward]

``check_certificates.py --unknowns`` searches with rules looser than the planner's (no rolling, the cone checked
where a step starts, the Omni's reach without slack, one contact place): an unknown it reaches may still have no
plan the fit can follow. This probe searches with the fit's own rules, from the planner's code:

- the holds of :func:`~tooltransfer.planner.planning.oe.guided_holds.lattice_rules` on windows of ``--span``
  (0.5 mm) of each face across its contact range less the contact margin, as many as cover it without gaps
  (``--windows`` 0; a positive number: at most that many, spread with gaps on the longer faces): the Omni
  reaching the contact at both ends of a window (with the search's ``REACH_SLACK``), the tool outline ``--room``
  from the obstacles there, the puck's centre its radius and the safety margin from them;
- straight steps of ``--step`` in ``--directions`` (nine) directions across each face's cone at ``--share`` of the
  friction cone (the ladder's middle share, :data:`~tooltransfer.planner.planning.oe.guided_rungs.MIDDLE_SHARE`),
  turned back inside the cone at the step's end (:func:`~tooltransfer.planner.planning.oe.guided_moves._stepped`),
  and from within three steps of the target a straight push onto it where the cone holds that direction at both
  of its ends (the guided search's last step); the target counts as reached within the hard check's goal
  tolerance (0.1 mm);
- the contact rolls from the window's middle as the inverse push model has it
  (:func:`~tooltransfer.planner.planning.oe.guided_moves._roll`), and the step's end must be held by the window
  of the face the rolled contact lies in (either of two where neighbouring windows overlap).

Each step may be a push of its own (the contact placed anew on any window that holds the puck): looser than the
planner there, since no re-contact or switch of face is checked. So "reached" does not mean that a plan exists,
and a closed space proves nothing either (the steps, directions and windows are discrete); what the probe tells is
whether an unknown is left open by the planner's search or by its rules. Weighted A* (the distance to go
weighted 2) on cells of half a step, once per face. Per task: the closest approach [mm], the expansions, whether
the space closed or the budget ran out, the CPU seconds. ``--backward`` runs the search the other way
(:func:`funnel`): from the target, each edge a step of the same rules, it tells how far from the target the
positions reach from which the steps end on it (the target's funnel; a forward search that comes near the target
outside it cannot end there at this resolution), and how near the start. Single-threaded BLAS. Exit code 0 (a
description, not a check); 2 for a results file that cannot be read.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import heapq
import math
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "benchmarks")]

from bench_execution import _task  # noqa: E402
from bench_verdicts import rows_with_verdict  # noqa: E402

from tooltransfer.planner.planning.oe.guided_rungs import MIDDLE_SHARE  # noqa: E402

#: Directions across each face's cone.
DIRECTIONS = 9
#: Weight of the distance to go in the search's order.
GREED = 2.0
#: How near [m] the target counts as reached: the hard check's goal tolerance (a plan ends on the target).
REACHED = 1e-4
#: ``windows`` of :func:`probe` that covers every face without gaps (:func:`contact_windows` takes as many as tile
#: the usable range, up to this).
TILED = 10001


def _probe_rules(setting: Any, options: Any, room: float, span: float, windows: int
                 ) -> tuple[Any, Any, Any, dict[str, list[Any]], Any]:
    """The probe's rules (module docstring): ``(held, free, by_key, of_face, lands)``, the first three as
    :func:`~tooltransfer.planner.planning.oe.guided_holds.lattice_rules` gives them on windows of ``span`` [m]
    (``windows``: the most per face, 0: as many as cover it), ``of_face``: the windows by face name, and
    ``lands(fm, p, q)``: whether the contact of
    window ``fm`` at ``p``, rolled over the step to ``q`` (2,) [m], lies in a window of its face that holds the
    puck at ``q``."""
    from tooltransfer.planner.planning.oe.guided_holds import lattice_rules
    from tooltransfer.planner.planning.oe.guided_moves import _roll

    held, free, by_key = lattice_rules(setting, options.model_copy(update={"contact_span": span}), True, None,
                                       room, windows or TILED)
    of_face: dict[str, list[Any]] = {}
    for fm in by_key.values():
        of_face.setdefault(fm.name, []).append(fm)

    def lands(fm: Any, p: Any, q: Any) -> bool:
        rolled = 0.5 * (fm.window[0] + fm.window[1]) + _roll(fm, p, q, setting.mechanics.rolling, setting.radius)
        ends = [e for e in of_face[fm.name] if e.window[0] - 1e-9 <= rolled <= e.window[1] + 1e-9]
        return any(held.holds(e, q) for e in ends)

    return held, free, by_key, of_face, lands


def _next_node(heap: list[tuple[float, float, int]], nodes: list[tuple[Any, str | None]],
               seen: set[tuple[int, int, str | None]], cell: float) -> tuple[float, int] | None:
    """The next node of a weighted A* on cells of side ``cell`` [m], once per face (``(cost so far, index into
    nodes)``, marked seen), or None once ``heap`` holds none not seen."""
    while heap:
        _, g, k = heapq.heappop(heap)
        p, came = nodes[k]
        key = (int(p[0] // cell), int(p[1] // cell), came)
        if key not in seen:
            seen.add(key)
            return g, k
    return None


def probe(setting: Any, options: Any, start: Any, target: Any, *, step: float, budget: int, room: float,
          span: float, windows: int, directions: int = DIRECTIONS) -> tuple[float, int, bool]:
    """``(closest approach [m], expansions, space closed)`` of the probe's search (module docstring) from ``start``
    to ``target`` (2,) [m] under the ``qp`` fit's ``options`` (its share of the friction cone and contact
    margin); ``windows``: the most per face (odd; 0: as many as cover each face); ``directions``: how many across
    each cone."""
    import numpy as np

    from tooltransfer.planner.planning.oe.guided_moves import _stepped

    held, free, by_key, _, lands = _probe_rules(setting, options, room, span, windows)
    cell = 0.5 * step

    def to_go(q: Any) -> float:
        return float(np.hypot(*(target - q)))

    nodes: list[tuple[Any, str | None]] = [(start, None)]
    heap = [(GREED * to_go(start), 0.0, 0)]
    seen: set[tuple[int, int, str | None]] = set()
    n, best = 0, to_go(start)
    while n < budget and (top := _next_node(heap, nodes, seen, cell)) is not None:
        g, k = top
        p = nodes[k][0]
        n += 1
        left = to_go(p)
        best = min(best, left)
        size = min(step, left)
        way = math.atan2(float(target[1] - p[1]), float(target[0] - p[0]))
        for name, mid, half in held(p):
            fm = by_key[name]
            angles = [(float(a), size, False) for a in mid + half * np.linspace(-1.0, 1.0, directions)]
            if left <= 3 * step and abs(math.remainder(way - mid, 2 * math.pi)) <= half:
                # straight onto the target, as the guided search's last step (nearer than a step: a step like the rest)
                angles.append((way, left, left > step))
            for ang, length, last in angles:
                q = _stepped(fm, p, ang, half, length)
                if q is None or not free(q) or (last and to_go(q) > REACHED):
                    continue  # (a last step turned back inside the cone misses the target)
                if not lands(fm, p, q):
                    continue
                if to_go(q) <= REACHED:
                    return to_go(q), n, False
                if (int(q[0] // cell), int(q[1] // cell), fm.name) in seen:
                    continue
                g2 = g + length
                nodes.append((q, fm.name))
                heapq.heappush(heap, (g2 + GREED * to_go(q), g2, len(nodes) - 1))
    return best, n, not heap


def funnel(setting: Any, options: Any, start: Any, target: Any, *, step: float, budget: int, room: float,
           span: float, windows: int, directions: int = DIRECTIONS, trace: list[Any] | None = None,
           ) -> tuple[float, float, int, bool]:
    """``(extent [m], closest to the start [m], expansions, space closed)`` of the probe's search run backward from
    ``target`` (2,) [m] (arguments as :func:`probe`; ``trace``: a list that receives ``(x, q, face, direction)``
    for every edge added, the step from ``x`` to the node ``q`` it was found from, its direction [rad]): the
    positions from which steps under the probe's rules end exactly on the target. From a node ``q`` it tries
    ``directions`` directions per face across the arc that the cones at ``q`` of the face's windows holding the
    puck there span; the step's start ``x = q - step * u`` is kept where a window of the same face holds the puck
    at ``x`` with the direction inside its cone at ``x`` and at ``q``, and the contact rolled over the step lands
    in a window holding the puck at ``q`` (:func:`_probe_rules`): every edge is a step of the forward probe's
    rules. Ordered toward ``start`` (weighted A*, as :func:`probe`); ``extent``: the farthest node from the
    target. A funnel that closes a few millimetres from the target says the target is reached, at this
    resolution, only from there: why a forward search that comes near it may still not end on it."""
    import numpy as np

    from tooltransfer.planner.planning.oe.guided_holds import CONE
    from tooltransfer.planner.planning.oe.guided_moves import _pointing

    held, free, by_key, windows_of, lands = _probe_rules(setting, options, room, span, windows)
    cell = 0.5 * step

    def inside(ang: float, mid: float, half: float) -> bool:
        return abs(math.remainder(ang - mid, 2 * math.pi)) <= half

    def to_start(q: Any) -> float:
        return float(np.hypot(*(start - q)))

    nodes: list[tuple[Any, str | None]] = [(target, None)]
    heap = [(GREED * to_start(target), 0.0, 0)]
    seen: set[tuple[int, int, str | None]] = set()
    n, best, extent = 0, to_start(target), 0.0
    while n < budget and (top := _next_node(heap, nodes, seen, cell)) is not None:
        g, k = top
        q = nodes[k][0]
        n += 1
        best, extent = min(best, to_start(q)), max(extent, float(np.hypot(*(q - target))))
        arcs: dict[str, tuple[float, float]] = {}  # per face, the arc its windows' cones at q span
        for name, mid, half in held(q):
            face = by_key[name].name
            lo, hi = arcs.get(face, (mid - half, mid + half))
            mid = lo + math.remainder(mid - lo, 2 * math.pi)
            arcs[face] = (min(lo, mid - half), max(hi, mid + half))
        for face, (lo, hi) in arcs.items():
            for ang in (float(a) for a in np.linspace(lo, hi, directions)):
                x = q - step * np.array([math.cos(ang), math.sin(ang)])
                if not free(x) or (int(x[0] // cell), int(x[1] // cell), face) in seen:
                    continue
                # a forward step from x: a window of the face holding the puck there, the direction in its cone at
                # both ends (the cheap tests first), its contact rolled onto a window that holds the puck at q
                if not any(inside(ang, _pointing(w, x), CONE * w.cone.theta_b)
                           and inside(ang, _pointing(w, q), CONE * w.cone.theta_b)
                           and held.holds(w, x) and lands(w, x, q) for w in windows_of[face]):
                    continue
                nodes.append((x, face))
                if trace is not None:
                    trace.append((x, q, face, ang))
                heapq.heappush(heap, (g + step + GREED * to_start(x), g + step, len(nodes) - 1))
    return extent, best, n, not heap


def _one(args: tuple[Any, float, dict[str, Any], bool]) -> tuple[str, tuple[float, ...], int, bool, float]:
    """``(task_id, distances [m], expansions, closed, CPU [s])`` of :func:`probe` (the distances: the closest
    approach) or, with ``backward``, :func:`funnel` (the extent and the closest to the start) on one job's task
    (``args``: the job, the share of the friction cone, the search's settings as :func:`probe` takes them,
    ``backward``)."""
    import numpy as np

    from tooltransfer.planner.planning.setting import setting_from_task, task_skills
    from tooltransfer.planner.planning.solve import qp_options

    job, share, settings, backward = args
    task = _task(job)
    setting = setting_from_task(task, task_skills(task, need_ss=False))
    options = qp_options(task).model_copy(update={"friction_cone_fraction": share})
    cpu = time.process_time()
    ends = np.array(task.start), np.array(task.target)
    if backward:
        extent, near, n, closed = funnel(setting, options, *ends, **settings)
        return job.task_id, (extent, near), n, closed, time.process_time() - cpu
    d, n, closed = probe(setting, options, *ends, **settings)
    return job.task_id, (d,), n, closed, time.process_time() - cpu


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a bench_verdicts.py --json file")
    ap.add_argument("--budget", type=int, default=60000, help="the search's expansions per task")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--step", type=float, default=0.003, help="the search's step [m]")
    ap.add_argument("--room", type=float, default=2.5e-4,
                    help="how far [m] the tool outline keeps from the obstacles (default: the hard check's)")
    ap.add_argument("--span", type=float, default=5e-4, help="the contact windows' width [m]")
    ap.add_argument("--windows", type=int, default=0,
                    help="the most windows per face (odd; 0: as many as cover each face without gaps)")
    ap.add_argument("--share", type=float, default=MIDDLE_SHARE,
                    help="the share of the friction cone's half-angle (default: the ladder's middle share)")
    ap.add_argument("--directions", type=int, default=DIRECTIONS, help="directions across each face's cone")
    ap.add_argument("--backward", action="store_true",
                    help="search backward from each target instead (funnel): how far from it the positions reach "
                         "from which the probe's steps end on it")
    args = ap.parse_args(argv)
    if not (0.0 < args.step < 0.05 and args.budget > 0 and args.room >= 0.0 and 0.0 < args.span < 0.05
            and (args.windows == 0 or (args.windows >= 1 and args.windows % 2 == 1))
            and 0.0 < args.share <= 1.0 and args.directions >= 2):
        ap.error("--step and --span must be in (0, 0.05) [m], --budget > 0, --room >= 0 [m], --windows 0 or odd, "
                 "--share in (0, 1], --directions >= 2")
    try:
        rows, jobs = rows_with_verdict(args.results, "unknown")
    except ValueError as exc:
        print(exc, file=sys.stderr)
        return 2
    reached: list[str] = []
    with ProcessPoolExecutor(args.workers) as pool:
        settings = {"step": args.step, "budget": args.budget, "room": args.room, "span": args.span,
                    "windows": args.windows, "directions": args.directions}
        todo = [(jobs[r["task_id"]], args.share, settings, args.backward) for r in rows]
        for tid, dist, n, closed, cpu in pool.map(_one, todo):
            if args.backward:
                extent, near = dist
                reached += [tid] if near <= REACHED else []
                end = "reached the start" if near <= REACHED else ("closed" if closed else "on its budget")
                print(f"{tid}: funnel reaches {extent * 1e3:.2f} mm from the target, {near * 1e3:.2f} mm from the "
                      f"start, after {n} expansions, {end} (CPU {cpu:.1f} s)", flush=True)
                continue
            d = dist[0]
            reached += [tid] if d <= REACHED else []
            end = "reached" if d <= REACHED else ("space closed" if closed else "on its budget")
            print(f"{tid}: closest {d * 1e3:.2f} mm after {n} expansions, {end} (CPU {cpu:.1f} s)", flush=True)
    print(f"\n{len(rows)} unknowns; under the fit's rules with rolling ({args.step * 1e3:g} mm steps, "
          f"{args.directions} directions at {args.share:g} of the friction cone, "
          f"{args.span * 1e3:g} mm windows, the tool {args.room * 1e3:g} mm from the obstacles) the probe "
          f"{'backward from the target reaches the start on' if args.backward else 'reaches'} {len(reached)}: "
          f"{reached}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
