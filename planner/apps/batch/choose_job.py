"""One task of a ``tools: choose`` batch inside a sandbox: the best of the batch's tools
(:func:`tooltransfer.planner.apps.choose.run.choose_tool`, in this process: the batch's slots already
use the cores) as a result row.

The row: ``status`` the choice's verdict (``solved`` when some tool solves the task), ``tool`` the chosen
one (``none`` when none does), ``reason`` (the best's, or every tool's verdict), the chosen plan's
metrics (:data:`tooltransfer.planner.apps.batch.execute.METRIC_COLUMNS`) and its executions
(``open_loop_*``, ``closed_loop_*``, ``sim_*``), ``time_total`` and ``cpu_time`` of the whole choice [s],
and under ``metrics_json`` the chosen plan's metrics with ``"choice"``: the ranking as ``choose --json``
gives it (:func:`tooltransfer.planner.apps.choose.report.summary`).
"""

from __future__ import annotations

import json
import time
from typing import Any

from tooltransfer.planner.apps.batch.execute import METRIC_COLUMNS, finite_or_none

#: The row's tool when no candidate solves the task.
NO_TOOL = "none"


def choose_job(task: dict[str, Any], source: str, oe: str, ss: str, tools: tuple[str, ...], seed: int = 0,
               tolerance: float = 0.01, budget: float = 1.0) -> dict[str, Any]:
    """Choose the best of ``tools`` for ``task`` (task-file fields, relative paths from ``source``'s
    folder) with the variants ``oe``/``ss``; ``seed``: the closed loops' camera noise; ``tolerance``
    [m]: ``sim_success`` of the open loop. Returns the row (module docstring)."""
    from tooltransfer.planner.apps.choose.report import summary
    from tooltransfer.planner.apps.choose.run import choose_tool
    from tooltransfer.problems.task import Variants, task_from_dict

    t = task_from_dict(task, source)
    t = t.model_copy(update={"variants": Variants(oe=oe, ss=ss)})
    wall, cpu = time.perf_counter(), time.process_time()
    choice = choose_tool(t, list(tools), workers=1, seed=seed, budget=budget)
    best = choice.best
    ranking = summary(choice)["ranking"]
    row: dict[str, Any] = {"status": choice.verdict, "tool": best.label if best else NO_TOOL,
                           "time_total": time.perf_counter() - wall, "cpu_time": time.process_time() - cpu}
    row["reason"] = "" if best else "; ".join(f"{e['tool']}: {e['verdict']}" for e in ranking)
    metrics: dict[str, Any] = dict(best.plan.metrics) if best and best.plan is not None else {}
    for k in METRIC_COLUMNS:
        row[k] = finite_or_none(metrics.get(k))
    if best is not None and best.plan is not None:
        row["n_switches"] = len(best.plan.switches)
        ex = best.executions
        runs = best.runs
        if ex is not None:
            ol = finite_or_none(ex.open_loop)
            row.update(open_loop_status=runs["open_loop"].status, open_loop_error=ol, sim_final_error=ol,
                       sim_success=None if ol is None else int(ol <= tolerance),
                       open_loop_wall_time=runs["open_loop"].wall,
                       closed_loop_status=runs["closed_loop"].status, closed_loop_reason=runs["closed_loop"].reason,
                       closed_loop_error=finite_or_none(ex.closed_loop), closed_loop_seed=seed,
                       closed_loop_wall_time=runs["closed_loop"].wall)
    row["metrics_json"] = json.dumps({**{k: (v if finite_or_none(v) is not None else str(v))
                                         for k, v in metrics.items()}, "choice": ranking}, default=str)
    return row
