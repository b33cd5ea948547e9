"""Compare the variants on a task: this project's QP/NLP (``qp/opt``) against the paper's mapping
(``mapping/opt``), or any OE/SS pairs, with the plan metrics side by side.

    python examples/compare_variants.py                                        # the transfer task
    python examples/compare_variants.py problems/paper/fig14_safety_margin.yaml --variants qp/opt mapping/opt qp/dmp
    python examples/compare_variants.py --simulate                             # and execute each open loop (MuJoCo)

Every pair plans the same task (skills learned once, cached); a pair that finds no plan prints its
reason instead of metrics (an infeasible plan is an answer, not a crash). ``tooltransfer compare``
does the four pairs with a figure; this is the loop to adapt when you want other metrics, tasks or
pairs, or a CSV of them (``--csv``).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

from tooltransfer import problems

TRANSFER = Path(problems.__file__).resolve().parent / "paper" / "transfer_tool2.yaml"

#: (metric key, label, scale, unit) shown per variant pair.
METRICS = (
    ("n_pushes", "pushes", 1, ""),
    ("n_recontacts", "re-contacts", 1, ""),
    ("goal_error", "goal error", 1e3, "mm"),
    ("deviation_mean", "mean deviation from the skill", 1e3, "mm"),
    ("cone_violation_max", "cone violation", 1, "rad"),
    ("friction_cone_margin_min", "friction-cone margin", 1, "rad"),
    ("self_consistency_max", "push-model replay error", 1e3, "mm"),
    ("obstacle_clearance_min", "object-obstacle clearance", 1e3, "mm"),
    ("tool_obstacle_clearance_min", "tool-obstacle clearance", 1e3, "mm"),
    ("switch_penetration_max", "switch penetration", 1e3, "mm"),
    ("path_length", "object path length", 1e3, "mm"),
    ("duration", "duration", 1, "s"),
    ("time_oe", "OE planning time", 1, "s"),
    ("time_total", "planning time", 1, "s"),
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("task", nargs="?", type=Path, default=TRANSFER, help="task file")
    ap.add_argument("--variants", nargs="+", default=["qp/opt", "mapping/opt"], help="OE/SS pairs")
    ap.add_argument("--simulate", action="store_true", help="execute each solved plan open loop on the MuJoCo platform")
    ap.add_argument("--csv", type=Path, help="write the table as CSV")
    args = ap.parse_args(argv)

    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task

    task = load_task(args.task)
    rows: dict[str, dict[str, object]] = {}
    for pair in args.variants:
        oe, ss = pair.split("/")
        variant = task.model_copy(update={"variants": task.variants.model_copy(update={"oe": oe, "ss": ss})})
        plan = solve(variant, args.task)
        row: dict[str, object] = {"status": plan.status, "reason": plan.reason}
        row.update({key: plan.metrics.get(key) for key, *_ in METRICS})
        if args.simulate and plan.status == "solved":
            from tooltransfer.planner.execution.simulate import simulate_plan

            row["open_loop_error"] = simulate_plan(plan).final_error
        rows[pair] = row

    width = max(len(label) + len(unit) + 3 for _, label, _, unit in METRICS)
    print(f"{task.name}: " + ", ".join(args.variants))
    print(f"{'':{width}}" + "".join(f"{pair:>14}" for pair in rows))
    print(f"{'status':{width}}" + "".join(f"{r['status']:>14}" for r in rows.values()))
    shown = [*METRICS, ("open_loop_error", "open-loop error (MuJoCo)", 1e3, "mm")] if args.simulate else METRICS
    for key, label, scale, unit in shown:
        name = f"{label} [{unit}]" if unit else label
        cells = []
        for r in rows.values():
            v = r.get(key)
            cells.append(f"{'-':>14}" if v is None else f"{float(v) * scale:>14.4g}")
        print(f"{name:{width}}" + "".join(cells))
    for pair, r in rows.items():
        if r["status"] != "solved":
            print(f"{pair}: {r['status']}: {r['reason']}")
    if args.csv is not None:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        with args.csv.open("w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=["variant", *next(iter(rows.values()))])
            w.writeheader()
            w.writerows({"variant": pair, **r} for pair, r in rows.items())
        print(f"wrote {args.csv}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
