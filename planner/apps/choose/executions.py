"""What a worker of a tool choice runs: planning one candidate, and one execution of a solved plan.

Both are module-level functions of picklable arguments, so a process pool runs them as they are;
each catches the candidate's own failures (an execution that raises becomes its status, an error in
planning an ``unknown`` verdict with the error as its reason) so that one tool never stops the choice.

The executions (:data:`MODES`): the open loop (:func:`tooltransfer.planner.execution.simulate.simulate_plan`)
and the closed loop (:func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`) on the nominal
MuJoCo platform, and the closed loop on a mismatched plant: the MuJoCo platform with the tool's
friction :data:`MISMATCH_FRICTION` ``tool_friction`` and the table's ``table_friction`` (the benchmarks'
mismatched platform, ``benchmarks/bench_execution.py``). The mismatched closed loop stays on MuJoCo: on
the quasi-static push model as the plant (:class:`tooltransfer.planner.execution.plant.ModelPlant`
with ``mu`` and ``c`` 0.6 or 1.4 times the plan's, the benchmarks' other mismatched plants) the loop
is no cheaper (measured 2026-12-04 on two solved plans: 1.7-5.4 s of CPU there against 3.9-4.3 s on
MuJoCo), since its re-plans and the push model's adaptation, not the physics, take most of its time.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from tooltransfer.planner.planning.plan import Plan
from tooltransfer.problems.task import Task

#: The executions of a solved plan, by the names :class:`.ranking.Executions` gives them.
MODES = ("open_loop", "closed_loop", "mismatch_closed_loop")
#: The mismatched plant's frictions (the nominal platform's: tool 0.8 against the puck, table 0.3).
MISMATCH_FRICTION = {"tool_friction": 0.5, "table_friction": 0.2}


@dataclass(frozen=True)
class Planned:
    """One candidate planned: its plan (None when planning raised), verdict, reason, wall and CPU time [s]."""

    plan: Plan | None
    verdict: str
    reason: str
    wall: float
    cpu: float


@dataclass(frozen=True)
class Executed:
    """One execution: the object's final distance to the target [m] (None when it raised), its status
    (``"done"`` for the open loop, the closed loop's own, or ``"exception: ..."``), reason and wall time [s]."""

    error: float | None
    status: str
    reason: str
    wall: float


def plan_candidate(task: Task, budget: float = 1.0, on_slow: Callable[[], None] | None = None) -> Planned:
    """Plan ``task`` (:func:`tooltransfer.planner.planning.solve.solve`, its ``on_slow``; relative paths
    from the task's file). A planner error is the candidate's ``unknown`` verdict, its message the reason."""
    from tooltransfer.planner.planning.solve import solve

    wall, cpu = time.perf_counter(), time.process_time()
    try:
        plan = solve(task, budget=budget, on_slow=on_slow)
    except Exception as exc:  # one tool's failure is its own verdict, never the choice's
        return Planned(None, "unknown", f"error while planning: {type(exc).__name__}: {exc}",
                       time.perf_counter() - wall, time.process_time() - cpu)
    return Planned(plan, plan.verdict, plan.reason or "", time.perf_counter() - wall, time.process_time() - cpu)


def execute(plan: Plan, mode: str, seed: int = 0) -> Executed:
    """Run the solved ``plan`` in ``mode`` (:data:`MODES`; ``seed``: the closed loop's camera noise)."""
    import numpy as np

    t0 = time.perf_counter()
    try:
        if mode == "open_loop":
            from tooltransfer.planner.execution.simulate import simulate_plan

            rep = simulate_plan(plan)
            return Executed(float(rep.final_error), "done", "", time.perf_counter() - t0)
        from tooltransfer.planner.execution.closed_loop import execute_closed_loop

        config: Any = None
        if mode == "mismatch_closed_loop":
            from tooltransfer.planner.execution.simulate import task_sim_config
            from tooltransfer.problems.task import task_from_dict

            config = task_sim_config(task_from_dict(plan.task, "plan.task"), **MISMATCH_FRICTION)
        elif mode != "closed_loop":
            raise ValueError(f"mode: expected one of {', '.join(MODES)}, got {mode!r}")
        cl = execute_closed_loop(plan, seed=seed, config=config)
        err = float(cl.final_error)
        return Executed(err if np.isfinite(err) else None, cl.status, cl.reason or "", time.perf_counter() - t0)
    except Exception as exc:  # an execution that raises fails, and says why
        return Executed(None, f"exception: {type(exc).__name__}", str(exc)[:300], time.perf_counter() - t0)
