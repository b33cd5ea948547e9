"""One task with one variant, planned (and executed) inside a sandbox process: the measures of a
result row (see :data:`tooltransfer.planner.apps.batch.store.RESULT_COLUMNS`).

Planning (:func:`execute_job`) and each execution of a solved plan (:func:`open_loop`,
:func:`closed_loop`) are separate sandbox calls (:class:`tooltransfer.planner.apps.batch.worker.Stage`), each with its
own timeout: an execution that raises, hangs or crashes the interpreter becomes that stage's
status and reason in the row, and the plan's own measures are kept. The plan goes from one call to
the next pickled (bytes), so the executor slots never unpickle planner objects.
"""

from __future__ import annotations

import json
import math
import pickle
import statistics
import time
from typing import Any

#: Plan metrics copied into result columns of the same name (absent ones stay NULL).
METRIC_COLUMNS = (
    "time_skills", "time_oe", "time_switches_and_timing", "n_qp", "cone_violation_max", "reach_violation_max",
    "obstacle_clearance_min", "switch_clearance_min", "switch_obstacle_clearance_min", "joint_limit_violation_max",
    "goal_error", "path_length", "n_pushes", "duration",
)


def finite_or_none(v: Any) -> float | None:
    """``v`` as a float if it is a finite number, else None (a NULL column: NaN, infinities, text,
    None and objects that are no number)."""
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def execute_job(task: dict[str, Any], source: str, oe: str, ss: str, keep_plan: bool = False,
                budget: float = 1.0) -> dict[str, Any]:
    """Plan ``task`` (task-file fields; relative paths are relative to ``source``'s folder) with the
    variants ``oe`` and ``ss``. Returns the row's measures: status, reason, times [s], the plan's
    metrics (SI units; infinities stored as NULL and kept in ``metrics_json``, beside the evidence and
    the object path's outline, :func:`path_outline`), switch count and penetration; with ``keep_plan``
    a solved plan also comes back pickled under ``"plan"`` (for the execution stages; not a column).
    ``budget``: :func:`~tooltransfer.planner.planning.solve.solve`'s (the search's and the
    certificate's budgets multiplied)."""
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import Variants, task_from_dict

    t = task_from_dict(task, source)
    t = t.model_copy(update={"variants": Variants(oe=oe, ss=ss)})
    wall, cpu = time.perf_counter(), time.process_time()
    plan = solve(t, source, budget=budget)
    row: dict[str, Any] = {"status": plan.status, "reason": plan.reason,
                           "time_total": time.perf_counter() - wall, "cpu_time": time.process_time() - cpu}
    m = plan.metrics
    for k in METRIC_COLUMNS:
        row[k] = finite_or_none(m.get(k))
    row["n_switches"] = len(plan.switches) if plan.status in ("solved", "violated") else None
    # penetration [m]: the switches' own report (the dmp switch variant may penetrate), or how far a
    # clearance goes below zero
    depth = [-float(v) for v in (m.get("switch_clearance_min"), m.get("switch_obstacle_clearance_min"),
                                 m.get("obstacle_clearance_min")) if finite_or_none(v) is not None]
    if finite_or_none(m.get("switch_penetration_max")) is not None:
        depth.append(float(m["switch_penetration_max"]))
    row["penetration_max"] = max(0.0, *depth) if depth else None
    evidence = {k: v for k, v in plan.evidence.items() if k != "certificate"}
    cert = plan.evidence.get("certificate")
    if cert:  # the certificate's kind, reason and rules; its polygons are in the plan file (solve -o)
        evidence["certificate"] = {k: cert[k] for k in ("kind", "reason", "rules", "start_gap") if k in cert}
    row["metrics_json"] = json.dumps({**{k: (v if finite_or_none(v) is not None else str(v)) for k, v in m.items()},
                                      "evidence": evidence, **path_outline(plan)})
    if keep_plan and plan.status == "solved":
        row["plan"] = pickle.dumps(plan, protocol=pickle.HIGHEST_PROTOCOL)
    return row


#: Most samples of the object path kept in a row (:func:`path_outline`).
PATH_SAMPLES = 60


def path_outline(plan: Any) -> dict[str, list[list[float]]]:
    """The planned object path of a whole plan (solved or violated) for the batch report's task
    panels: ``{"object_path": [[x, y], ...]}`` [m], at most :data:`PATH_SAMPLES` samples evenly spaced
    in the plan's samples (the first and the last kept), rounded to 0.1 mm; ``{}`` without a path."""
    xy = getattr(plan, "object_xy", None)
    if plan.status not in ("solved", "violated") or xy is None or len(xy) == 0:
        return {}
    import numpy as np

    idx = np.unique(np.linspace(0, len(xy) - 1, min(len(xy), PATH_SAMPLES)).round().astype(int))
    return {"object_path": np.round(np.asarray(xy, dtype=float)[idx], 4).tolist()}


def open_loop(plan: bytes, tolerance: float = 0.01) -> dict[str, Any]:
    """Execute the pickled solved plan open loop on the simulated platform: ``open_loop_error`` [m]
    (object to target at the end), ``open_loop_status`` ``"done"``, and the same under the schema-1
    names ``sim_final_error``, ``sim_tool_deviation`` [m], ``sim_wall_time`` [s] and ``sim_success``
    (within ``tolerance`` [m])."""
    from tooltransfer.planner.execution.simulate import simulate_plan

    rep = simulate_plan(pickle.loads(plan))
    err = finite_or_none(rep.final_error)
    return {"open_loop_status": "done", "open_loop_error": err, "sim_final_error": err,
            "sim_tool_deviation": finite_or_none(rep.tool_deviation), "sim_wall_time": rep.wall_time,
            "sim_success": None if err is None else int(err <= tolerance)}


def closed_loop(plan: bytes, seed: int, tolerance: float = 0.001, camera_noise: float = 0.0015) -> dict[str, Any]:
    """Execute the pickled solved plan closed loop on the simulated platform (camera noise
    ``camera_noise`` [m] per frame, seed ``seed``; stops within ``tolerance`` [m] as measured): the
    ``closed_loop_*`` columns (status ``reached|closest|rounds|failed`` and its reason, the true final
    error [m], pushes, switches, re-contacts, re-plans and their median time [s])."""
    from tooltransfer.planner.execution.closed_loop import execute_closed_loop

    rep = execute_closed_loop(pickle.loads(plan), tolerance=tolerance, camera_noise=camera_noise, seed=seed)
    times = [float(x) for x in rep.replan_times]
    return {"closed_loop_status": rep.status, "closed_loop_reason": rep.reason, "closed_loop_seed": seed,
            "closed_loop_error": finite_or_none(rep.final_error), "closed_loop_pushes": rep.n_pushes,
            "closed_loop_switches": rep.n_switches, "closed_loop_recontacts": rep.n_recontacts,
            "closed_loop_replans": rep.n_replans,
            "closed_loop_replan_time_median": statistics.median(times) if times else None,
            "closed_loop_replan_time_max": max(times) if times else None}


def warm_up(simulate: bool = False) -> None:
    """Import what :func:`execute_job` (and with ``simulate`` the executions) need (run once when a
    sandbox starts)."""
    import tooltransfer.planner.planning.solve

    if simulate:
        import tooltransfer.planner.execution.closed_loop
        import tooltransfer.planner.execution.simulate  # noqa: F401
