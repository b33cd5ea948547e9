"""Every certificate of a verdict run against an independent search: a feasible task called infeasible
is the worst defect a verdict can have, so each one is checked by code the planner does not use.

Run after the verdict benchmark (``make bench-verdicts`` or ``python benchmarks/bench_verdicts.py --json
RESULTS``)::

    python benchmarks/check_certificates.py RESULTS.json [--budget 15000] [--workers 2] [--dense] [--unknowns]
        [--goal-disc G]

For every task the run called ``infeasible`` (whatever the certificate's kind) the task is generated
again from its batch file and the test suite's own lattice search
(``tests/test_verdicts.py::lattice_search``: straight pushes of 3 mm in five directions across each
face's whole friction cone cut by its tool-file cone, the cone's edges first, from the tool yaws at
which the Omni holds the face with the contact at places along its range and the tool outline clear of
the obstacles, to a position the face still holds, the puck kept its clearance from the obstacles;
breadth first, one visit per 1.5 mm cell) pushes the puck from the start. It is looser than the
planner's rules (no contact rolling, no tool sweep between its ends, no switches: any face at any node)
and coarser where it cannot be exact (its steps and cells), so it proves nothing either way. Two things
are reported per task:

* the certificate's own test: the certificate is made again, and every position the search reaches is
  tried against it: for ``backward_reachable``, how deep it lies inside the certificate's set (the set
  of positions a plan to the target could start from: a position the search reaches there means a push
  entered a set the certificate says no push enters; flagged beyond :data:`DEPTH_TOL`); for
  ``polar_invariant``, how far below the start's value the certificate's quantity is there (a quantity
  no push decreases; flagged beyond :data:`V_TOL` or half the way to the target's goal disc: a straight
  step along a cone's edge lowers it by a little, about the square of the step, as the cone turns with
  the heading over the step, and many such steps add up to a milliradian or so); for ``switch_separated``
  (sets of the positions each face could push the puck to from the start, switches only where the tool
  gets round the puck), the search is ``tests/test_switch_forward.py::switch_lattice_search`` instead (the
  same steps on states of a cell and a face, the face changed only where a brute-force grid of the tool's
  placements finds a way round the puck), and how far outside the sets it reaches is flagged beyond
  :data:`DEPTH_TOL`; for ``forward_backward`` (on log-polar cells, the positions a plan from the start could
  reach within those from which the target could be reached), how far outside the first set any position the
  search reaches inside the second lies, flagged beyond :data:`DEPTH_TOL`. For the kinds without a set (the
  start or the target where no face holds the puck) the search is flagged where it comes within
  ``--flag`` of the target;
* the closest approach to the target [mm], and how many come within ``--flag`` (3 mm, the test suite's
  threshold): a sound certificate whose set or quantity passes close to the target may be approached
  this close, so this number is a description, not a test, where the certificate has its own.

With ``--goal-disc G`` [m] every certificate is also made again with a goal disc of radius ``G`` instead
of the hard check's ``goal_tol`` (0.1 mm): the stronger claim that no plan ends within ``G`` of the target.
How many still hold is printed (a description: a certificate is relative to ``goal_tol``, so one that does
not hold at a wider disc is not flagged); a checker that accepts plans ending farther from the target
than the hard check does can see which certificates its own tolerance leaves standing.

The exit code is 1 when any certificate is flagged. Single-threaded BLAS; CPU seconds per task are
printed. ``--dense`` searches denser (nine directions, every one of 13 contact places, 0.75 mm cells);
give it a larger ``--budget``.

With ``--unknowns`` the same search runs on the tasks the run left ``unknown`` instead, and the report
counts how many of them it comes within ``--flag`` of: what the unknowns are made of. ``--share`` and
``--room`` narrow its rules there to margins a plan could keep (part of the friction cone, the tool
outline that far from the obstacles): an unknown reached even so is not one that only pushes at the edge
of the cone or with the tool touching an obstacle could do. Reached by a
search that ignores the contact's rolling, the tool's sweep and the switches, an unknown is likely
feasible with plans this planner's own narrower rules do not make (the contact at a face's tip, pushes
at the very edge of the cone); not reached, it is a candidate for a tighter certificate. Nothing is
flagged as an error in this mode (exit code 0): an unknown is allowed to be either.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "benchmarks"), str(ROOT / "tests")]

from bench_execution import _task  # noqa: E402
from bench_verdicts import rows_with_verdict  # noqa: E402

#: The dense search's settings (``--dense``): nine directions in each cone, every one of 13 contact
#: places, cells of 0.75 mm (the default search: five directions, every third of the yaws that hold the
#: puck with the contact at 7 places, 1.5 mm).
DENSE = {"directions": 9, "contacts": 13, "yaw_stride": 1, "cell": 0.00075}
#: How deep [m] a position the search reaches may lie inside a ``backward_reachable`` certificate's set
#: before it is flagged: a straight step of 3 mm along a cone's edge leaves the cone by the heading's turn
#: over the step (about 2 degrees at most, at the reach's inner edge), so it may cut a set's boundary by
#: about 0.1 mm.
DEPTH_TOL = 5e-4
#: How far [rad] below the start's value a ``polar_invariant`` certificate's quantity may be at a position
#: the search reaches before it is flagged (or half the certificate's gap, if less): straight steps along
#: a cone's edge lower it by about the square of the step each, 0.98 mrad at most over the 13 invariants of
#: the verdict benchmark's run (benchmarks/README.md).
V_TOL = 5e-3
#: The kinds whose sets hold what a plan from the start could reach (the search must stay inside them).
FORWARD_KINDS = ("switch_separated", "forward_backward")


def _switches(setting: Any, rules: Any, start: Any, target: Any, budget: int) -> tuple[float, float, dict[str, Any]]:
    """For a ``switch_separated`` certificate: the test suite's lattice search on states of a cell and a face,
    changing faces only where a brute-force grid of the tool's placements finds a way round the puck
    (``tests/test_switch_forward.py::switch_lattice_search``), and how far outside the certificate's sets
    (made again) any position it reaches lies (``depth``, flagged as a set's depth is)."""
    import numpy as np
    import shapely
    from test_switch_forward import switch_lattice_search

    from tooltransfer.planner.planning.verdicts.certificate import certify_switches
    from tooltransfer.planner.planning.verdicts.switch_space import placement_space

    cpu = time.process_time()
    visited: list[Any] = []
    d, _, _ = switch_lattice_search(setting, start, target, budget=budget, visited=visited)
    cpu = time.process_time() - cpu
    cert = certify_switches(rules, placement_space(setting), start, target)[0]
    test: dict[str, Any] = {"kind": None if cert is None else cert.kind, "depth": None, "v_low": None,
                            "v_goal": None}
    if cert is not None and cert.region is not None and visited:
        test["depth"] = float(shapely.distance(cert.region, shapely.points(np.asarray(visited))).max())
    return d, cpu, test


def _outside_ahead(cert: Any, pts: Any) -> float:
    """For a ``forward_backward`` certificate: how far [m of its log-polar plane] outside its set ``F`` (the
    positions a plan from the start could reach within ``B``) the farthest of the positions ``pts`` (K, 2) [m]
    the search reaches from the start lies, of those inside ``B`` (the positions from which the target could
    be reached: a position outside it cannot lie on a plan); 0 where none lies outside."""
    import shapely

    from tooltransfer.planner.planning.verdicts.polar_sets import stored_sets

    lp, back, ahead = stored_sets(cert.rules["base"], cert.extra)
    at = shapely.points(lp.forward(pts))
    inside = shapely.covers(back, at)
    return float(shapely.distance(ahead, at[inside]).max()) if inside.any() else 0.0


def _made_with_goal(setting: Any, rules: Any, start: Any, target: Any, goal: float) -> str | None:
    """The kind of the certificate the verdict's attempts make (in its order: the default sets, the exact
    backward set, the switch sets) with a goal disc of radius ``goal`` [m] in ``rules``; None: none is made."""
    from dataclasses import replace

    from tooltransfer.planner.planning.verdicts.certificate import certify
    from tooltransfer.planner.planning.verdicts.decide import later_attempts

    wide = replace(rules, goal_tol=goal)
    cert = certify(wide, start, target)[0]
    for attempt in later_attempts(wide, setting, start, target):
        cert = cert or attempt()[0]
    return None if cert is None else cert.kind


def _closest(args: tuple[Any, int, bool, bool, float, float, str | None, float | None]
             ) -> tuple[str, float, float, dict[str, Any]]:
    """``(task_id, closest approach [m], CPU [s], the certificate's own test)`` of the lattice search
    (``dense``: :data:`DENSE`; steps whose end the face still holds) on one job's task. The test: the
    task's certificate made again (as the verdict run made it) and every position the search reaches
    tried against it: ``depth`` [m], the deepest inside a ``backward_reachable`` set; ``v_low`` [rad],
    the least value of a ``polar_invariant``'s quantity less its value at the start (both None for the
    other kinds, where no certificate is made, and for ``unknowns``, where none is made). The CPU time is
    the search's (not the certificate's). ``share``, ``room``: :func:`lattice_search`'s (1 and 0 but for
    ``unknowns``). ``goal``: a goal disc [m] to make the certificate again with (``test["wide"]``: its kind,
    or None; :func:`_made_with_goal`), or None."""
    import numpy as np
    from test_verdicts import _rules_of, depth_inside, lattice_search

    from tooltransfer.planner.planning.verdicts.certificate import certify, certify_both_ways, certify_exact_backward
    from tooltransfer.planner.planning.verdicts.spiral import Spiral, _values

    job, budget, dense, unknowns, share, room, kind, goal = args
    task = _task(job)
    setting, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    wide = {} if goal is None else {"wide": _made_with_goal(setting, rules, start, target, goal)}
    if kind == "switch_separated":
        tid, d, cpu, test = job.task_id, *_switches(setting, rules, start, target, budget)
        return tid, d, cpu, test | wide
    cpu = time.process_time()
    visited: list[Any] = []
    d = lattice_search(setting, start, target, budget=budget, ends_held=True, visited=visited, share=share,
                       room=room, **(DENSE if dense else {}))
    cpu = time.process_time() - cpu
    cert = None if unknowns else certify(rules, start, target)[0]
    if cert is None and not unknowns and kind == "backward_reachable":  # the verdict's last backward attempt
        cert = certify_exact_backward(rules, start, target)[0]
    if cert is None and not unknowns and kind == "forward_backward":  # the verdict's last attempt
        cert = certify_both_ways(rules, start, target)[0]
    test: dict[str, Any] = {"kind": None if cert is None else cert.kind, "depth": None, "v_low": None,
                            "v_goal": None}
    pts = np.asarray(visited)
    if cert is not None and cert.kind == "backward_reachable" and cert.region is not None:
        test["depth"] = depth_inside(cert.region, pts)
    elif cert is not None and cert.kind == "forward_backward":
        test["depth"] = _outside_ahead(cert, pts)
    elif cert is not None and cert.kind == "polar_invariant":
        sp = Spiral.from_dict(cert.extra["invariant"])
        test["v_low"] = min(_values(rules, sp, p, p)[0] for p in pts) - sp.v_start
        test["v_goal"] = sp.v_goal - sp.v_start
    return job.task_id, d, cpu, test | wide


def _own(test: dict[str, Any]) -> str:
    """The certificate's own test, printed."""
    if test["depth"] is not None:
        where = "farthest outside its sets" if test["kind"] in FORWARD_KINDS else "deepest inside its set"
        return f"; {where} {test['depth'] * 1e3:.2f} mm"
    if test["v_low"] is not None:
        return (f"; its quantity at least {test['v_low'] * 1e3:+.2f} mrad from the start's value "
                f"(the target's at most {test['v_goal'] * 1e3:+.2f})")
    return ""


def _wide(test: dict[str, Any], goal: float | None) -> str:
    """The certificate made again with the goal disc ``goal`` [m] (``--goal-disc``), printed."""
    if goal is None:
        return ""
    return f"; with a goal disc of {goal * 1e3:g} mm: {test.get('wide') or 'not made'}"


def _wide_problem(test: dict[str, Any], d: float, goal: float | None) -> str:
    """"" unless a certificate made with the goal disc ``goal`` [m] says no plan ends within it while the
    search comes that close to the target (``d`` [m])."""
    if goal is None or not test.get("wide") or d > goal:
        return ""
    return f"made with a goal disc of {goal * 1e3:g} mm, but the search comes within {d * 1e3:.2f} mm of the target"


def _verdict_of(test: dict[str, Any], kind: str | None, d: float, flag: float) -> str:
    """"" where the search is consistent with the certificate, else what is wrong (module docstring)."""
    if test["kind"] != kind:
        return f"the certificate is not made again ({test['kind']} instead of {kind})"
    if test["depth"] is not None and not test["depth"] <= DEPTH_TOL:  # NaN flagged too
        where = "outside the certificate's sets from the start" if kind in FORWARD_KINDS else \
            "inside the certificate's set"
        return f"the search reaches {test['depth'] * 1e3:.2f} mm {where}"
    if test["v_low"] is not None and not test["v_low"] >= -min(V_TOL, -0.5 * test["v_goal"]):
        low = "as low as the target's" if test["v_low"] <= test["v_goal"] else f"more than {V_TOL * 1e3:g} mrad " \
            "or half the way to the target's"
        return f"the search goes {-test['v_low'] * 1e3:.2f} mrad below the start's value of the invariant, {low}"
    if test["depth"] is None and test["v_low"] is None and d <= flag:
        return f"the search comes within {flag * 1e3:g} mm of the target"
    return ""


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a bench_verdicts.py --json file")
    ap.add_argument("--budget", type=int, default=15000, help="the lattice search's expansions per task")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--flag", type=float, default=0.003, help="flag a task the search comes this close to [m]")
    ap.add_argument("--dense", action="store_true",
                    help="a denser search (nine directions, every contact place of 13, 0.75 mm cells; slower)")
    ap.add_argument("--unknowns", action="store_true",
                    help="search on the tasks left unknown instead (a description, not a check)")
    ap.add_argument("--share", type=float, default=1.0,
                    help="with --unknowns: the share (0, 1] of the friction cone's half-angle the search pushes in")
    ap.add_argument("--room", type=float, default=0.0,
                    help="with --unknowns: how far [m] the tool outline keeps from the obstacles")
    ap.add_argument("--goal-disc", type=float, default=None,
                    help="also make every certificate again with a goal disc of this radius [m] (a stronger claim)")
    args = ap.parse_args(argv)
    narrowed = (args.share, args.room) != (1.0, 0.0)  # the lattice's rules narrower than the certificates'
    if narrowed and not args.unknowns:
        ap.error("--share and --room narrow the rules: a certificate is checked under its own (use them with "
                 "--unknowns)")
    if args.goal_disc is not None and (args.unknowns or not 0.0 < args.goal_disc < 1.0):
        ap.error(f"--goal-disc is a radius in (0, 1) [m] for the certificates (not with --unknowns), "
                 f"got {args.goal_disc}")
    if not 0.0 < args.share <= 1.0 or not args.room >= 0.0:
        ap.error(f"--share must be in (0, 1] and --room >= 0 [m], got {args.share} and {args.room}")
    verdict = "unknown" if args.unknowns else "infeasible"
    try:
        rows, jobs = rows_with_verdict(args.results, verdict)
    except ValueError as exc:
        print(exc, file=sys.stderr)
        return 2
    kind = {r["task_id"]: r.get("evidence_kind") for r in rows}
    found: list[tuple[str, float, float]] = []
    wrong: list[str] = []
    held: list[str] = []  # (--goal-disc) the certificates made again with the wider goal disc
    with ProcessPoolExecutor(args.workers) as pool:
        todo = [(jobs[r["task_id"]], args.budget, args.dense, args.unknowns, args.share, args.room, kind[r["task_id"]],
                 args.goal_disc) for r in rows]
        for tid, d, cpu, test in pool.map(_closest, todo):
            found.append((tid, d, cpu))
            if args.unknowns:
                mark = "  reached" if d <= args.flag else ""
            else:
                problem = _verdict_of(test, kind[tid], d, args.flag) or _wide_problem(test, d, args.goal_disc)
                wrong += [tid] if problem else []
                mark = _own(test) + _wide(test, args.goal_disc) + (f"  FLAGGED: {problem}" if problem else "")
                held += [tid] if test.get("wide") else []
            print(f"{tid} {kind[tid] or verdict}: closest {d * 1e3:.2f} mm (CPU {cpu:.1f} s){mark}", flush=True)
    if not found:
        print(f"no {'unknown' if args.unknowns else 'certificate'} in the run")
        return 0
    flagged = [t for t, d, _ in found if d <= args.flag]
    if args.unknowns:
        rules = f", at {args.share:g} of the friction cone, the tool {args.room * 1e3:g} mm from the obstacles" \
            if narrowed else ""
        print(f"\n{len(found)} unknowns; the lattice search (no rolling, no tool sweep, no switches{rules}) comes "
              f"within {args.flag * 1e3:g} mm of the target on {len(flagged)}; not on {len(found) - len(flagged)}: "
              f"{[t for t, d, _ in found if d > args.flag]}")
        return 0
    print(f"\n{len(found)} certificates; the lattice search's closest approach: min "
          f"{min(d for _, d, _ in found) * 1e3:.2f} mm; within {args.flag * 1e3:g} mm: {len(flagged)} {flagged}; "
          f"inconsistent with their own certificate: {len(wrong)} {wrong}")
    if args.goal_disc is not None:
        print(f"made again with a goal disc of {args.goal_disc * 1e3:g} mm: {len(held)} of {len(found)}; not: "
              f"{[t for t, _, _ in found if t not in held]}")
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
