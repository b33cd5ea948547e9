"""A SYNTHETIC batch store for measuring the batch report's size and speed: ``n_tasks`` tasks x the
four variants, written with the real store API (:class:`~tooltransfer.planner.apps.batch.store.ResultStore`),
but the rows are made up (random statuses, times, errors, reasons with numbers, 60-sample object
paths), not planned. Seeded: the same store for the same arguments. Never use it for a result.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from tooltransfer.planner.apps.batch.store import ResultStore

VARIANTS = ("mapping/dmp", "mapping/opt", "qp/dmp", "qp/opt")
#: Centre of the synthetic tasks' region [m].
CENTRE = np.array([0.0, 0.15])
_STATUSES = ("solved", "solved", "solved", "infeasible", "unknown", "violated", "error", "timeout")


def synthetic_store(path: Path, n_tasks: int, seed: int = 0) -> Path:
    """Write the synthetic store (module docstring) to ``path`` (a new file); returns it."""
    rng = np.random.default_rng(seed)
    with ResultStore(path) as store:
        store.set_meta(batch_name=f"synthetic_{n_tasks}", schema="2")
        tasks = []
        for i in range(n_tasks):
            start, target = rng.uniform(-0.08, 0.08, 2) + CENTRE, rng.uniform(-0.08, 0.08, 2) + CENTRE
            obstacles = [{"kind": "disc", "centre": (rng.uniform(-0.05, 0.05, 2) + CENTRE).round(4).tolist(),
                          "radius": 0.005} for _ in range(int(rng.integers(0, 4)))]
            doc = {"format": "tooltransfer.task/1", "name": f"t{i:05d}", "tool": "slope",
                   "start": start.round(4).tolist(), "target": target.round(4).tolist(), "obstacles": obstacles}
            tasks.append({"task_id": f"synthetic-{i:05d}", "idx": i, "tool": "slope", "n_obstacles": len(obstacles),
                          "reach_margin": float(rng.uniform(0, 0.03)), "distance": float(np.hypot(*(target - start))),
                          "task_json": json.dumps(doc)})
        store.add_tasks(tasks)
        for t in tasks:
            doc = json.loads(t["task_json"])
            s, g = np.array(doc["start"]), np.array(doc["target"])
            for v in VARIANTS:
                status = str(rng.choice(_STATUSES))
                row = {"task_id": t["task_id"], "variant": v, "oe": v.split("/")[0], "ss": v.split("/")[1],
                       "tool": "slope", "status": status, "time_total": float(rng.lognormal(-0.5, 0.8))}
                if status in ("solved", "violated"):
                    k = np.linspace(0, 1, 60)[:, None]
                    xy = s + k * (g - s) + 0.01 * np.sin(np.pi * k) * rng.normal(size=2)
                    row.update(goal_error=float(rng.uniform(0, 5e-4)), cone_violation_max=0.0,
                               open_loop_status="done", open_loop_error=float(rng.lognormal(-7, 1)),
                               closed_loop_status="reached", closed_loop_error=float(rng.lognormal(-8, 0.5)),
                               metrics_json=json.dumps({"goal_error": 1e-4, "n_pushes": 2,
                                                        "object_path": xy.round(4).tolist()}))
                    if status == "violated":
                        row["reason"] = f"hard checks violated: cone (cone_violation_max {rng.uniform(0, 1):.4f} " \
                                        "rad > 0.01)"
                else:
                    row["reason"] = {"infeasible": f"reach: the target is {rng.uniform(1, 30):.2f} mm outside the "
                                     "workspace of every face of the tool (certificate backward_reachable)",
                                     "unknown": f"the guided search spent its budget ({int(rng.integers(100, 900))} "
                                     "expansions) without a plan; no certificate either",
                                     "error": "ValueError: a synthetic error",
                                     "timeout": "timed out after 60 s"}[status]
                store.put(row)
    return path
