"""Plan a task with a tool of your own: a tool YAML, the paper's transfer scene, one plan file.

The tool file (``examples/tool_files/spatula.yaml``, or yours with ``--tool``) is checked as the planner
reads it (a simple outline, faces on it, angles in range: :func:`tools.load_tool` names the field of
any error). The task is the paper's transfer case (``problems/paper/transfer_tool2.yaml``: tool 1's
demonstrations, its start, target and obstacle) with the tool replaced by an inline copy of the
file, so the task file written next to the plan stands alone:

    python examples/plan_with_a_new_tool.py                          # the spatula, qp/opt
    python examples/plan_with_a_new_tool.py --tool my_tool.yaml --variant mapping/opt --out out/mine
    tooltransfer solve out/examples/new_tool/task.yaml               # the same task from the CLI

It prints the push sequence and the checks, and writes ``task.yaml``, ``plan.json`` and, with
``--plot``, the plan's figure.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import yaml

from tooltransfer import problems
from tooltransfer.tools import load_tool

HERE = Path(__file__).resolve().parent
SCENE = Path(problems.__file__).resolve().parent / "paper" / "transfer_tool2.yaml"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tool", type=Path, default=HERE / "tool_files" / "spatula.yaml", help="tool YAML")
    ap.add_argument("--scene", type=Path, default=SCENE, help="task file whose scene to plan")
    ap.add_argument("--variant", default="qp/opt", help="OE/SS variant, e.g. qp/opt or mapping/dmp")
    ap.add_argument("--out", type=Path, default=Path("out/examples/new_tool"), help="output folder")
    ap.add_argument("--plot", action="store_true", help="draw the plan (Fig. 12 style)")
    args = ap.parse_args(argv)

    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import resolve, task_from_dict

    tool = load_tool(args.tool)
    print(f"tool {tool.name!r}: a_t {1e3 * tool.a_t:.0f} mm, faces "
          + ", ".join(f"{f.name} ({1e3 * f.length:.1f} mm, pushes at {f.push_angle:.2f} rad)" for f in tool.faces))

    task_doc = yaml.safe_load(args.scene.read_text())
    task_doc["tool"] = yaml.safe_load(args.tool.read_text())      # inline: the task file stands alone
    task_doc["name"] = f"{task_doc['name']}_{tool.name}"
    oe, ss = args.variant.split("/")
    task_doc["variants"] = {"oe": oe, "ss": ss}
    if "dataset" in task_doc["skills"]:                            # relative to the scene's file: absolute
        task_doc["skills"]["dataset"] = str(resolve(args.scene, task_doc["skills"]["dataset"]).resolve())
    args.out.mkdir(parents=True, exist_ok=True)
    task_file = args.out / "task.yaml"
    task_file.write_text(yaml.safe_dump(task_doc, sort_keys=False))
    task = task_from_dict(task_doc, str(task_file))

    plan = solve(task, task_file)
    m = plan.metrics
    print(f"{task.name} ({args.variant}): {plan.status}" + (f": {plan.reason}" if plan.status != "solved" else ""))
    if plan.status == "solved":
        print("  pushes: " + " -> ".join(p.faces[0] for p in plan.pushes) + f" ({int(m['n_recontacts'])} re-contacts)")
        print(f"  duration {m['duration']:.1f} s, goal error {1e3 * m['goal_error']:.3f} mm, "
              f"push model replay within {1e3 * m['self_consistency_max']:.3f} mm, "
              f"friction-cone margin {m['friction_cone_margin_min']:.3f} rad, "
              f"tool-obstacle clearance {1e3 * m['tool_obstacle_clearance_min']:.1f} mm")
        print(f"  planned in {m['time_total']:.2f} s (skills {m['time_skills']:.2f} s, OE {m['time_oe']:.2f} s)")
    plan_file = plan.write(args.out / "plan.json")
    print(f"wrote {task_file} and {plan_file}")
    if args.plot and plan.status == "solved":
        from tooltransfer.planner.apps.plots.execution import plot_plan

        print(f"wrote {plot_plan(plan, args.out / 'plan.png')}")
    return 0 if plan.status == "solved" else 1


if __name__ == "__main__":
    raise SystemExit(main())
