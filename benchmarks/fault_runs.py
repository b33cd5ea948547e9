"""The closed loop on fault plants, for ``bench_execution.py --faults``: runs and their report.

Each solved plan runs closed loop on the base plant (the MuJoCo platform, or the quasi-static push
model with the plan's mechanics: ``--fault-base``) wrapped in each fault of
:data:`tooltransfer.planner.execution.fault_plants.FAULTS` named, with a recorder outside the fault
that keeps every command the loop sent. Per run: the status and reason, the true final error, the
commands sent, those whose tool outline overlaps an obstacle or that leave the Omni's reach
(checked on their straight pieces from the reported pose, sampled every 0.5 mm with the Omni's
heading), whether an exception left ``execute_closed_loop``, the plant time from the fault's start
to the end of the run, and whether the tool ended clear of the object.

The report checks the targets of issue 27: no command overlapping an obstacle or leaving the reach,
every run ending with a status and no exception, the recoverable faults
(:data:`~tooltransfer.planner.execution.fault_plants.RECOVERABLE`) within 3 mm in at least 90 % of
runs, and a frozen camera ended ``sensor_fault`` within 2 s of plant time with the tool clear of
the object.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager
from typing import Any

import numpy as np

from tooltransfer.planner.execution.fault_plants import FAULTS, RECOVERABLE

Row = dict[str, Any]
FAULT_BASES = ("sim", "model")
RECOVER_WITHIN = 0.003
"""Final-error threshold [m] of the recoverable faults."""
FROZEN_WITHIN = 2.0
"""Plant time [s] within which a frozen camera must end the run."""


class Recorder:
    """The plant the loop is given: passes everything on to ``plant`` and keeps each command the
    loop sent with the pose the tool reported before it."""

    def __init__(self, plant: Any) -> None:
        self.plant = plant
        self.commands: list[np.ndarray] = []

    def observe_object(self) -> Any:
        return self.plant.observe_object()

    def tool_pose(self) -> Any:
        return self.plant.tool_pose()

    def move_tool(self, t: np.ndarray, tool_pose: np.ndarray) -> None:
        try:
            start = np.asarray(self.plant.tool_pose(), dtype=float)[:3]
        except Exception:
            start = np.asarray(tool_pose, dtype=float)[0]
        self.commands.append(np.vstack([start, tool_pose]))
        self.plant.move_tool(t, tool_pose)

    def true_object(self) -> Any:
        return self.plant.true_object()

    @property
    def execution(self) -> object:
        return getattr(self.plant, "execution", None)


def parse_faults(text: str) -> tuple[str, ...]:
    """``"all"`` or comma-separated names of :data:`FAULTS` -> the names."""
    if text.strip() == "all":
        return tuple(FAULTS)
    names = tuple(n.strip() for n in text.split(","))
    unknown = [n for n in names if n not in FAULTS]
    if unknown:
        raise ValueError(f"faults: {unknown} are not among {list(FAULTS)} (or 'all')")
    return names


def _command_checks(setting: Any, commands: Sequence[np.ndarray]) -> tuple[int, int]:
    """Commands whose tool outline overlaps an obstacle, and commands leaving the Omni's reach."""
    from tooltransfer.planner.execution.envelope import densify
    from tooltransfer.planner.planning.tool_clearance import tool_obstacle_clearance
    from tooltransfer.tools.omni.ik import joint_path

    overlap = reach = 0
    for c in commands:
        xy = densify(c[:, :2])
        jp = joint_path(setting.platform, xy)
        reach += bool(np.any(jp.refused))
        ok = np.isfinite(jp.heading)
        if setting.obstacles and ok.any():
            poses = np.column_stack([xy[ok], jp.heading[ok]])
            overlap += tool_obstacle_clearance(setting.tool, poses, setting.obstacles).distance <= 0.0
    return overlap, reach


def run_faults(plan: Any, mech: Any, names: Sequence[str], base: str, seed: int,
               deadline: Callable[[str], AbstractContextManager[None]]) -> dict[str, Row]:
    """Run a solved plan closed loop on each fault of ``names`` over the ``base`` plant (module
    docstring); ``deadline(what)`` bounds each run (the benchmark's ``--timeout``)."""
    from tooltransfer.planner.execution.closed_loop import execute_closed_loop
    from tooltransfer.planner.execution.fault_plants import fault_plant
    from tooltransfer.planner.execution.health import penetration
    from tooltransfer.planner.execution.plant import ModelPlant, sim_plant
    from tooltransfer.planner.execution.simulate import task_sim_config
    from tooltransfer.planner.planning.setting import setting_from_task
    from tooltransfer.problems.task import task_from_dict

    task = task_from_dict(plan.task, "plan.task")
    setting = setting_from_task(task, mechanics=mech)
    out: dict[str, Row] = {}
    for name in names:
        res: Row = {"status": None, "reason": "", "error": None, "commands": 0, "overlapping": None,
                    "out_of_reach": None, "escaped": None, "after_fault": None, "tool_clear": None}
        t0 = time.perf_counter()
        try:
            if base == "sim":
                inner = sim_plant(setting, task_sim_config(task), task.start, plan.joints[0], 0.0015, seed)
            else:
                inner = ModelPlant(setting.tool, setting.radius, mech, task.start, plan.tool_pose[0],
                                   platform=setting.platform, camera_noise=0.0015, seed=seed)
            fp = fault_plant(name, inner, seed=seed, obstacles=setting.obstacles, radius=setting.radius,
                             margin=setting.margin, target=task.target)
            rec = Recorder(fp)
            with deadline(f"closed loop on fault {name}"):
                rep = execute_closed_loop(plan, rec, seed=seed)
            res.update(status=rep.status, reason=rep.reason, error=float(rep.final_error), escaped=False)
            overlap, reach = _command_checks(setting, rec.commands)
            res.update(commands=len(rec.commands), overlapping=overlap, out_of_reach=reach)
            if fp.fault_time is not None:
                res["after_fault"] = fp.plant_time - fp.fault_time
            pen = penetration(setting.tool, np.asarray(inner.tool_pose()), np.asarray(inner.true_object()),
                              setting.radius)
            res["tool_clear"] = bool(pen < 0.0)
        except Exception as exc:
            res.update(escaped=True, reason=f"{type(exc).__name__}: {exc}"[:300])
        res["wall"] = time.perf_counter() - t0
        out[name] = res
    return out


def fault_table(con: Any, solved: Sequence[Row]) -> None:
    """The fault plants' table over the solved plans' ``faults`` results (generated and paper tasks),
    and the targets."""
    from rich import box
    from rich.table import Table

    runs = [(name, r) for row in solved for name, r in (row.get("faults") or {}).items()]
    if not runs:
        return
    t = Table("fault", "runs", "statuses", f"<= {1e3 * RECOVER_WITHIN:.0f} mm", "overlapping", "out of reach",
              "escaped", "after fault s (max)", "tool clear", title="closed loop on the fault plants",
              box=box.SIMPLE_HEAD, title_justify="left")
    for name in dict.fromkeys(n for n, _ in runs):
        rs = [r for n, r in runs if n == name]
        ok = sum(r["error"] is not None and r["error"] <= RECOVER_WITHIN for r in rs)
        after = [r["after_fault"] for r in rs if r["after_fault"] is not None]
        statuses = Counter(r["status"] or "exception" for r in rs)
        t.add_row(name + (" (recoverable)" if name in RECOVERABLE else ""), str(len(rs)),
                  ", ".join(f"{s} {n}" for s, n in statuses.most_common()), f"{ok}/{len(rs)}",
                  str(sum(r["overlapping"] or 0 for r in rs)), str(sum(r["out_of_reach"] or 0 for r in rs)),
                  str(sum(bool(r["escaped"]) for r in rs)), f"{max(after):.2f}" if after else "-",
                  f"{sum(bool(r['tool_clear']) for r in rs)}/{len(rs)}")
    con.print(t)
    all_rs = [r for _, r in runs]
    safe = sum(r["overlapping"] or 0 for r in all_rs) == 0 and sum(r["out_of_reach"] or 0 for r in all_rs) == 0
    ended = all(r["status"] is not None and not r["escaped"] for r in all_rs)
    rec = [r for n, r in runs if n in RECOVERABLE]
    rec_ok = sum(r["error"] is not None and r["error"] <= RECOVER_WITHIN for r in rec)
    frozen = [r for n, r in runs if n == "frozen camera"]
    frozen_ok = all(r["status"] == "sensor_fault" and r["after_fault"] is not None
                    and r["after_fault"] <= FROZEN_WITHIN and r["tool_clear"] for r in frozen)
    con.print(f"targets: no command overlapping an obstacle or leaving the reach: {'met' if safe else 'MISSED'}; "
              f"every run ends with a status, no exception: {'met' if ended else 'MISSED'}; "
              f"recoverable faults within {1e3 * RECOVER_WITHIN:.0f} mm: {rec_ok}/{len(rec)} "
              f"({'met' if rec and rec_ok >= 0.9 * len(rec) else 'MISSED'}, >= 90 %); frozen camera ended "
              f"sensor_fault within {FROZEN_WITHIN:.0f} s of plant time, tool clear: "
              f"{sum(r['status'] == 'sensor_fault' for r in frozen)}/{len(frozen)} "
              f"({'met' if frozen and frozen_ok else 'MISSED'})")
