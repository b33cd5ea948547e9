"""One task with one variant, planned (and simulated) inside a sandbox process: the measures of a
result row (see :data:`planner.batch.store.RESULT_COLUMNS`)."""

from __future__ import annotations

import json
import math
import time
from typing import Any

#: Plan metrics copied into result columns of the same name (absent ones stay NULL).
METRIC_COLUMNS = (
    "time_skills", "time_oe", "time_switches_and_timing", "n_qp", "cone_violation_max", "reach_violation_max",
    "obstacle_clearance_min", "switch_clearance_min", "switch_obstacle_clearance_min", "joint_limit_violation_max",
    "goal_error", "path_length", "n_pushes", "duration",
)


def _finite(v: Any) -> float | None:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def execute_job(task: dict[str, Any], source: str, oe: str, ss: str, simulate: bool = False,
                tolerance: float = 0.01) -> dict[str, Any]:
    """Plan ``task`` (task-file fields; relative paths are relative to ``source``'s folder) with the
    variants ``oe`` and ``ss``; simulate a solved plan when ``simulate``. Returns the row's measures:
    status, reason, times [s], the plan's metrics (SI units; infinities stored as NULL and kept in
    ``metrics_json``), switch count, penetration and, if simulated, the final error [m] and success
    (final error within ``tolerance`` [m])."""
    from planner.solve import solve
    from problems.task import Variants, task_from_dict

    t = task_from_dict(task, source)
    t = t.model_copy(update={"variants": Variants(oe=oe, ss=ss)})
    wall, cpu = time.perf_counter(), time.process_time()
    plan = solve(t, source)
    row: dict[str, Any] = {"status": plan.status, "reason": plan.reason,
                           "time_total": time.perf_counter() - wall, "cpu_time": time.process_time() - cpu}
    m = plan.metrics
    for k in METRIC_COLUMNS:
        row[k] = _finite(m.get(k))
    row["n_switches"] = len(plan.switches) if plan.status == "solved" else None
    # penetration [m]: the switches' own report (the dmp switch variant may penetrate), or how far a
    # clearance goes below zero
    depth = [-float(v) for v in (m.get("switch_clearance_min"), m.get("switch_obstacle_clearance_min"),
                                 m.get("obstacle_clearance_min")) if _finite(v) is not None]
    if _finite(m.get("switch_penetration_max")) is not None:
        depth.append(float(m["switch_penetration_max"]))
    row["penetration_max"] = max(0.0, *depth) if depth else None
    row["metrics_json"] = json.dumps({k: (v if _finite(v) is not None else str(v)) for k, v in m.items()})
    if simulate and plan.status == "solved":
        from planner.simulate import simulate_plan

        rep = simulate_plan(plan)
        row.update({"sim_final_error": rep.final_error, "sim_tool_deviation": rep.tool_deviation,
                    "sim_wall_time": rep.wall_time, "sim_success": int(rep.final_error <= tolerance)})
    return row


def warm_up(simulate: bool = False) -> None:
    """Import what :func:`execute_job` needs (run once when a sandbox starts)."""
    import planner.solve

    if simulate:
        import planner.simulate  # noqa: F401
