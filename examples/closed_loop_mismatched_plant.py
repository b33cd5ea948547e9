"""Closed loop on a plant the plan mispredicts, through the ``Plant`` protocol.

The plan is made with the push mechanics identified from the demonstrations (``mu``, ``c``). The
plant here is :class:`tooltransfer.planner.execution.plant.ModelPlant`: the quasi-static push model with ``mu`` and
``c`` scaled (0.6x by default), a camera with 1.5 mm noise per frame, and the Omni's joint limits
checked on every commanded path. The same plan is executed twice on it:

* open loop: the whole planned tool path at once, the way the paper executed its plans;
* closed loop: :func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`, which pushes a chunk, observes
  the puck, re-plans the rest when it is off the plan, and identifies ``mu`` and ``c`` again when the
  model mispredicts.

The plant is wrapped in :class:`LoggedPlant`, a class of its own with the protocol's three methods:
the shape a driver for a real device takes (``observe_object`` from the camera, ``tool_pose`` from
the encoders, ``move_tool`` streaming the path to the arm's controller and returning when done).

    python examples/closed_loop_mismatched_plant.py                    # the transfer task, 0.6 x mu and c
    python examples/closed_loop_mismatched_plant.py --scale 1.4 --seed 7
    python examples/closed_loop_mismatched_plant.py --mu 0.5 --c 0.4   # absolute values instead
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from tooltransfer import problems
from tooltransfer.planner.execution.plant import ModelPlant, Plant

TRANSFER = Path(problems.__file__).resolve().parent / "paper" / "transfer_tool2.yaml"


class LoggedPlant:
    """A plant of one's own: forwards to another plant and logs what the loop asks of it."""

    def __init__(self, inner: ModelPlant) -> None:
        self.inner = inner
        self.moves = 0
        self.observations = 0
        self.commanded_time = 0.0

    def observe_object(self) -> NDArray[np.float64]:
        """The object's centre (2,) [m] in the world frame, as the camera sees it (noisy)."""
        self.observations += 1
        return self.inner.observe_object()

    def tool_pose(self) -> NDArray[np.float64]:
        """The tool pose (3,): ``x, y`` [m], ``yaw`` [rad], from the encoders."""
        return self.inner.tool_pose()

    def move_tool(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        """Track ``tool_pose`` (K, 3) at times ``t`` (K,) [s] from 0; return when done. Raising a
        ``ToolTransferError`` (e.g. a driver fault) ends the closed loop with that reason."""
        self.moves += 1
        self.commanded_time += float(t[-1])
        self.inner.move_tool(t, tool_pose)

    def true_object(self) -> NDArray[np.float64]:
        """Not part of the protocol: the simulated plant knows the true centre (for the report)."""
        return self.inner.true_object()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("task", nargs="?", type=Path, default=TRANSFER, help="task file")
    ap.add_argument("--scale", type=float, default=0.6, help="plant's mu and c as multiples of the plan's")
    ap.add_argument("--mu", type=float, help="plant's mu (instead of --scale)")
    ap.add_argument("--c", type=float, help="plant's c (instead of --scale)")
    ap.add_argument("--noise", type=float, default=0.0015, help="camera noise per frame [m]")
    ap.add_argument("--seed", type=int, default=3, help="camera noise seed")
    args = ap.parse_args(argv)

    from tooltransfer.planner.execution.closed_loop import execute_closed_loop
    from tooltransfer.planner.planning.solve import solve
    from tooltransfer.problems.task import load_task, task_platform, task_tool
    from tooltransfer.tools.pushing.mechanics import PushMechanics

    task = load_task(args.task)
    plan = solve(task, args.task)
    if plan.status != "solved":
        print(f"{task.name}: {plan.status}: {plan.reason}")
        return 1
    tool = task_tool(task)
    mu, c = plan.metrics["mechanics_mu"], plan.metrics["mechanics_c"]
    plant_mech = PushMechanics(args.mu if args.mu is not None else args.scale * mu,
                               args.c if args.c is not None else args.scale * c)
    print(f"{task.name}: planned with mu {mu:.2f}, c {c:.2f}; the plant has mu {plant_mech.mu:.2f}, "
          f"c {plant_mech.c:.2f}, camera noise {1e3 * args.noise:.1f} mm")

    def plant() -> ModelPlant:
        return ModelPlant(tool, task.object.radius, plant_mech, task.start, plan.tool_pose[0],
                          platform=task_platform(task, tool), camera_noise=args.noise, seed=args.seed)

    open_loop = plant()
    open_loop.move_tool(plan.t - plan.t[0], plan.tool_pose)           # the whole plan, no feedback
    ol_error = float(np.hypot(*(open_loop.true_object() - np.asarray(task.target))))
    print(f"open loop:   object {1e3 * ol_error:6.2f} mm from the target")

    logged = LoggedPlant(plant())
    assert isinstance(logged, Plant)                                  # the protocol is runtime-checkable
    start = time.perf_counter()
    rep = execute_closed_loop(plan, logged, camera_noise=args.noise, seed=args.seed)
    print(f"closed loop: object {1e3 * rep.final_error:6.2f} mm from the target, {rep.status}"
          + (f" ({rep.reason})" if rep.reason else ""))
    print(f"  {rep.n_pushes} push chunks, {rep.n_switches} switches, {rep.n_recontacts} re-contacts, "
          f"{rep.n_replans} re-plans (median {1e3 * np.median(rep.replan_times or [0.0]):.0f} ms), "
          f"{logged.moves} moves ({logged.commanded_time:.1f} s of motion), {logged.observations} camera frames, "
          f"{time.perf_counter() - start:.1f} s of computing")
    if rep.mechanics is not None:
        print(f"  push model at the end: mu {rep.mechanics.mu:.2f}, c {rep.mechanics.c:.2f} "
              f"(adapted {len(rep.adapt_times)} times)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
