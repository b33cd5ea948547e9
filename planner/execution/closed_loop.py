"""Closed-loop execution as receding-horizon re-planning with the planner itself (model predictive control).

The plan's pushes are executed a chunk at a time through a :class:`tooltransfer.planner.execution.plant.Plant` (the
MuJoCo platform by default, a mismatched quasi-static model in tests, a real Omni with a camera).
After each chunk the loop observes the resting object (the mean of ``frames`` camera frames) and
re-solves the rest of the task from there with the same condensing as the plan:

1. the rest of the plan's object path, shifted to start at the observed object and blended back to
   the target, with the rest of the plan's faces and switch times
   (:class:`tooltransfer.planner.planning.oe.replan.PlanReference`): with the QP variant one fit of that
   sequence (:func:`tooltransfer.planner.planning.oe.qp_variant.condense_sequence`, the contact starting where the
   face already touches the object), and when it fails a new search from here; another variant
   re-plans with its own condensing. Re-plans use the push model in force (adapted on line when it
   mispredicts: :mod:`tooltransfer.tools.pushing.adaptation`) and :mod:`tooltransfer.planner.planning.oe.replan`'s
   options; a re-plan is put in force only where its tool keeps the safety envelope's margin along every push and
   its first change of face has a tool path (:meth:`tooltransfer.planner.execution.loop_run.LoopRun.runnable`);
2. the next chunk: the first push of that re-plan, at most ``chunk`` of object travel (and at most
   ``approach`` of what is left once the target is near, so the object comes at it from short of it:
   faces cannot pull back), its tool path from the push model (the re-plan's tool poses); a change of
   face is a switch planned at the observed object with the plan's SS variant, another contact point
   of the same face a re-contact;
3. when the plan's path is used up and the object is not within ``tolerance``: correction rounds
   from the observed object to the target along the faces' normals (one face, or the corner of two
   faces' normals that splits the way: pushes along a normal go where they are aimed whatever the
   limit surface is), a new search when none fits, at most ``max_rounds``; a correction the object
   strays from by more than the re-plan threshold is made again from where the object is.

It ends ``"reached"`` (the measured object within ``tolerance``: between two chunks in a look confirmed by
:data:`~tooltransfer.planner.execution.loop_steps.CONFIRM_LOOKS` looks averaged, in a last look of ``FINAL_LOOKS``
observations for a run that ended otherwise), ``"closest"`` (no push sequence brings it closer),
``"rounds"`` (``max_rounds`` used up) or ``"failed"`` (a move refused by the planners, or a plant
method that raised; the reason says which).

The plant misbehaving is part of the loop's design, not an exception to it:

* every tool command goes through a :class:`~tooltransfer.planner.execution.guarded_plant.GuardedPlant`,
  the only plant the run holds, which never sends a command that leaves the
  :class:`~tooltransfer.planner.execution.envelope.SafetyEnvelope` (the obstacles grown against the
  tool's outline, the Omni's reach and joint limits, the table); such a command ends the run
  ``"unsafe"``;
* the looks are robust and judged (:mod:`tooltransfer.planner.execution.health`): dropped frames are
  taken again, outliers left out, a noisy camera looked at longer; a frozen camera ends the run
  ``"sensor_fault"``, a tool that does not follow its command ``"tracking_fault"``, an object
  displaced into an obstacle's margin ``"disturbed"`` (elsewhere the loop re-plans from where it is
  seen); after these the tool backs off the object along the contact's normal, inside the envelope;
* no exception leaves :func:`execute_closed_loop` but ``KeyboardInterrupt``, after the tool was
  stopped (the plant's ``stop()`` when it has one, else a command to stay where it is): a plant
  that raises or returns values of the wrong shape or not finite ends the run with a reason naming
  the method and the value (:mod:`tooltransfer.planner.execution.loop_stop`), and the report keeps
  everything observed until then.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from tooltransfer.errors import InputError
from tooltransfer.planner.execution.envelope import ENVELOPE_MARGIN
from tooltransfer.planner.execution.loop_run import LoopRun as _Loop
from tooltransfer.planner.execution.loop_steps import InForce as _InForce
from tooltransfer.planner.execution.loop_steps import Pace as _Pace
from tooltransfer.planner.execution.loop_steps import next_chunk as _next_chunk
from tooltransfer.planner.execution.loop_steps import plan_done, plan_the_rest
from tooltransfer.planner.execution.loop_stop import LoopStop
from tooltransfer.planner.execution.plant import Plant
from tooltransfer.planner.planning.oe.replan import PlanReference
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.problems.task import task_from_dict

if TYPE_CHECKING:
    from tooltransfer.tools.sim import SimConfig

__all__ = ["FINAL_LOOKS", "ClosedLoopReport", "execute_closed_loop"]

T = TypeVar("T")

#: Observations in the last look of a run that did not see the object at the target (noise halved).
FINAL_LOOKS = 4


@dataclass(frozen=True)
class ClosedLoopReport:
    """Outcome of a closed-loop execution.

    Attributes:
        status: ``"reached"``, ``"closest"``, ``"rounds"``, ``"failed"``, ``"unsafe"``,
            ``"sensor_fault"``, ``"tracking_fault"`` or ``"disturbed"`` (module docstring).
        reason: why it did not reach the target (empty when it did).
        final_error: object centre to target at the end [m] (the true one when the plant tells it,
            else the measured one; the last look's when neither can be had now, NaN without any).
        n_pushes: chunks pushed; n_switches: changes of face; n_recontacts: re-contacts of a face.
        n_replans: re-plans solved; replan_times: their wall times [s].
        errors: object-to-target distance [m] after each chunk.
        wall_time: [s]; execution: the plant's recording when it keeps one (the MuJoCo platform).
        log: what the loop decided along the way; mechanics: the push model in force at the end (the
        plan's, or the adapted one); adapt_times: wall times [s] of the adaptations.
    """

    status: str
    reason: str
    final_error: float
    n_pushes: int
    n_switches: int
    n_recontacts: int
    n_replans: int
    replan_times: list[float]
    errors: list[float]
    wall_time: float
    execution: object = None
    log: list[str] = field(default_factory=list)
    mechanics: object = None
    adapt_times: list[float] = field(default_factory=list)


def _safely(what: str, fn: Callable[[], T], loop: _Loop) -> T | None:
    """``fn()``, or None when it raises (noted in the run's log): the report is made whatever the plant does."""
    try:
        return fn()
    except Exception as exc:
        loop.log.append(f"{what} not made: {type(exc).__name__}: {exc}")
        return None


def _report(status: str, reason: str, loop: _Loop | None, plant: Plant | None, tolerance: float,
            start: float) -> ClosedLoopReport:
    """The run's report (module docstring: the last look, made only for a run that ended without a
    fault). ``start``: the run's ``perf_counter`` [s]. A final error the plant cannot tell is the last
    look's (NaN without any)."""
    if loop is None:
        return ClosedLoopReport(status, reason, float("nan"), 0, 0, 0, 0, [], [], time.perf_counter() - start,
                                getattr(plant, "execution", None) if plant is not None else None)
    err = _safely("the final error", loop.true_error, loop)
    if err is None:
        seen = loop.last_seen
        err = float(np.hypot(*(loop.target - seen))) if seen is not None else float("nan")
    if status in ("closest", "rounds", "failed"):
        last = _safely("the last look", lambda: np.mean([loop.observe() for _ in range(FINAL_LOOKS)], axis=0), loop)
        if last is not None and np.hypot(*(loop.target - last)) <= tolerance:
            status, reason = "reached", ""
    return ClosedLoopReport(
        status, reason, float(err), loop.n_pushes, loop.n_switches, loop.n_recontacts, len(loop.replan_times),
        loop.replan_times, loop.errors, time.perf_counter() - start, loop.plant.execution, loop.log,
        loop.setting.mechanics, loop.adaptation.times)


def execute_closed_loop(
    plan: Plan, plant: Plant | None = None, *, tolerance: float = 0.001, chunk: float = 0.015,
    approach: float = 0.6, max_rounds: int = 4, max_chunks: int = 120, frames: int = 10,
    replan_threshold: float = 0.001, adapt: bool = True, camera_noise: float = 0.0015, seed: int = 0,
    config: SimConfig | None = None, envelope_margin: float = ENVELOPE_MARGIN,
) -> ClosedLoopReport:
    """Execute a solved plan closed loop (module docstring).

    Args:
        plan: a solved plan (its task names the skills by absolute path, as :func:`tooltransfer.planner.planning.solve`
            writes it).
        plant: a :class:`tooltransfer.planner.execution.plant.Plant` with the object at the task's start and the tool
            at the plan's first pose; default the MuJoCo platform (``config``: its
            :class:`tooltransfer.tools.sim.SimConfig`, default the task's object) with a camera of
            ``camera_noise`` [m] per frame (seed ``seed``).
        tolerance: the object counts as at the target within this distance [m] (as measured).
        chunk: longest object travel [m] of one chunk before the object is observed again.
        approach: share of the remaining path a chunk may push once less than two chunks remain.
        max_rounds: correction rounds once the plan's path is used up; max_chunks: chunks in all.
        frames: camera frames averaged per observation.
        replan_threshold: the rest is re-planned when the observed object is farther than this [m]
            (or three times the averaged camera noise, if more) from where the plan in force puts it;
            closer, the plan in force goes on (re-planning on the camera's noise would only add it).
        adapt: identify ``mu`` and ``c`` again from the executed chunks when the model mispredicts one
            by more than :data:`tooltransfer.tools.pushing.adaptation.ADAPT_ERROR`, so the re-plans use
            the plant's mechanics (the report's ``mechanics``; the identifications' times ``adapt_times``).
        camera_noise: the camera's noise per frame [m]: the default plant's, and the noise the re-plan
            threshold and the adaptation's prior (:mod:`tooltransfer.tools.pushing.adaptation`) assume
            for any plant.
        envelope_margin: the least distance [m] between the tool's outline and the obstacles along
            every command (:class:`tooltransfer.planner.execution.envelope.SafetyEnvelope`).
    """
    if not isinstance(plan, Plan) or plan.status != "solved":
        raise InputError("plan", "a solved plan", getattr(plan, "status", type(plan).__name__))
    start = time.perf_counter()
    task = task_from_dict(plan.task, "plan.task")
    status, reason = "rounds", ""
    loop: _Loop | None = None
    try:
        loop = _Loop(plan, task, plant, frames, tolerance, adapt, camera_noise, seed, config, envelope_margin)
        status, reason = _run(loop, plan, _Pace(tolerance, max(replan_threshold, 3.0 * camera_noise / np.sqrt(frames)),
                                                chunk, approach, max_rounds), max_chunks)
    except KeyboardInterrupt:
        if loop is not None:
            loop.plant.hold()
        raise
    except LoopStop as stop:
        status, reason = stop.status, stop.reason
        if loop is not None and stop.retreat:
            try:
                loop.retreat()
            except Exception as exc:  # the run is ending with its fault: the failed retreat is noted
                loop.log.append(f"no retreat: {type(exc).__name__}: {exc}")
    except Exception as exc:  # no exception escapes: anything else ends the run with its reason
        status, reason = "failed", f"{type(exc).__name__}: {exc}"
    return _report(status, reason, loop, plant, tolerance, start)


def _run(loop: _Loop, plan: Plan, pace: _Pace, max_chunks: int) -> tuple[str, str]:
    """The loop of the module docstring from the plan's first pose: the run's ``(status, reason)``
    unless a :class:`LoopStop` ends it."""
    approach_m = np.asarray(plan.phase) == "approach"
    loop.move(plan.tool_pose[approach_m, :2])
    loop.face = plan.pushes[0].faces[0]
    ref = PlanReference.of(plan)
    f = _InForce(ref.plan)
    for _ in range(max_chunks):
        if plan_the_rest(loop, ref, f):
            continue
        if f.i >= len(f.plan.pushes):
            ended = plan_done(loop, ref, f, pace)
            if ended is not None:
                return ended
            continue
        if _next_chunk(loop, ref, f, pace):
            return "reached", ""
    return "rounds", f"{max_chunks} chunks did not reach the target"
