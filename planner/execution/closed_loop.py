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
   options and obstacle check;
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

It ends ``"reached"`` (the measured object within ``tolerance``, in a last look of ``FINAL_LOOKS``
observations for a run that ended otherwise), ``"closest"`` (no push sequence brings it closer),
``"rounds"`` (``max_rounds`` used up) or ``"failed"`` (a move refused; the reason says which).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError, ToolTransferError
from tooltransfer.planner.execution.plant import Plant
from tooltransfer.planner.planning.oe.correction import correction_references
from tooltransfer.planner.planning.oe.mapping_variant import MappingOptions
from tooltransfer.planner.planning.oe.push_plan import Push, PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.replan import (
    QP_REPLAN_SIZES,
    PlanReference,
    refuse_tool_overlap,
    replan_options,
    replan_setting,
)
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.planner.planning.setting import setting_from_task, task_skills
from tooltransfer.planner.planning.ss.arch_variant import swept_clearance
from tooltransfer.planner.planning.variant_registry import needs_ss_skill, oe_variant, switch_planner
from tooltransfer.problems.task import Task, task_from_dict
from tooltransfer.timing import min_jerk_along, min_jerk_duration
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.pose import rotation
from tooltransfer.tools.pushing.adaptation import Adaptation

if TYPE_CHECKING:
    from tooltransfer.tools.sim import SimConfig

#: Tool moves shorter than this [m] between a chunk's end and the next chunk's start are skipped.
SAME_POSE = 3e-4
#: How far [m] the tool first backs off along the contact's normal before a switch or a re-contact.
BACK_OFF = 0.002
#: Once the model has mispredicted two chunks, the last this many metres are pushed along the faces'
#: normals (:meth:`_Loop.correction`).
STAGE = 0.025
#: Observations in the last look of a run that did not see the object at the target (noise halved).
FINAL_LOOKS = 4


@dataclass(frozen=True)
class ClosedLoopReport:
    """Outcome of a closed-loop execution.

    Attributes:
        status: ``"reached"``, ``"closest"``, ``"rounds"`` or ``"failed"`` (module docstring).
        reason: why it did not reach the target (empty when it did).
        final_error: object centre to target at the end [m] (the true one when the plant tells it,
            else the measured one).
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


class _Loop:
    """One closed-loop run (see :func:`execute_closed_loop`)."""

    def __init__(self, plan: Plan, task: Task, plant: Plant | None, frames: int, tolerance: float,
                 adapt: bool = True, camera_noise: float = 0.0015, seed: int = 0,
                 config: SimConfig | None = None) -> None:
        from tooltransfer.planner.planning.recontact import recontact_planner
        from tooltransfer.planner.planning.switches import with_fallback

        ss = plan.variant.get("ss", task.variants.ss)
        skills = task_skills(task, need_ss=needs_ss_skill(ss))
        self.setting = setting_from_task(task, skills)  # the world, as solve builds it
        self.tool, self.platform = self.setting.tool, self.setting.platform
        if plant is None:
            from tooltransfer.planner.execution.plant import sim_plant
            from tooltransfer.planner.execution.simulate import task_sim_config

            plant = sim_plant(self.setting, config or task_sim_config(task), task.start, plan.joints[0], camera_noise,
                              seed)
        self.plant = plant
        self.frames, self.tolerance, self.noise = frames, tolerance, camera_noise / np.sqrt(frames)
        self.switch = switch_planner(ss, self.setting, skills.ss, task.ss)
        self.recontact = with_fallback(recontact_planner(self.setting), self.switch, "switch")
        self.target = np.array(task.target)
        self.oe = oe_variant(plan.variant.get("oe", task.variants.oe))
        self.options = self.oe.options_from_task(task.oe)
        if isinstance(self.options, QPOptions):  # the QP variant's smaller fits, for re-plans made often
            self.options = self.options.model_copy(update=QP_REPLAN_SIZES)
        self.c_plan = self.setting.mechanics.c
        self.v, self.a = task.timing.max_tool_speed, task.timing.max_tool_accel
        self.face: str | None = None
        self.adapt = adapt
        self.pending: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self.before: NDArray[np.float64] | None = None
        self.adaptation = Adaptation(self.tool, self.setting.radius, self.noise)
        self.staged = False
        self.n_pushes = self.n_switches = self.n_recontacts = 0
        self.replan_times: list[float] = []
        self.errors: list[float] = []
        self.log: list[str] = []

    # ---------------------------------------------------------------- sensing and moving
    def observe(self) -> NDArray[np.float64]:
        """The resting object as the camera measures it: the mean of ``frames`` frames."""
        return np.mean([self.plant.observe_object() for _ in range(self.frames)], axis=0)

    def true_error(self) -> float:
        here = getattr(self.plant, "true_object", None)
        o = here() if callable(here) else self.observe()
        return float(np.hypot(*(self.target - o)))

    def move(self, xy: NDArray[np.float64], record: bool = False) -> None:
        """Track the tool path ``xy`` (K, 2) [m] (heading from the Omni) with a minimum-jerk profile
        (``record``: keep the commanded poses and times, a push for the adaptation)."""
        length = float(np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1)))
        if length < 1e-6:
            return
        dur = min_jerk_duration(length, self.v, self.a)
        n = max(3, int(np.ceil(dur / 0.01)) + 1)
        t, path = min_jerk_along(xy, dur, n)
        jp = joint_path(self.platform, path)
        bad = np.flatnonzero(jp.refused)
        if bad.size:
            raise InputError("tool path", "a move within the Omni's reach and joint limits",
                             f"{np.round(path[bad[0]], 4).tolist()} m")
        poses = np.column_stack([path, jp.heading])
        self.plant.move_tool(t, poses)
        if record:
            self.pending = (t, poses)

    # ---------------------------------------------------------------- planning
    def replan_options(self) -> QPOptions | MappingOptions:
        """The re-plans' options: the friction cone's share widened, the plan's contact budget carried
        over to the push model in force (:func:`tooltransfer.planner.planning.oe.replan.replan_options`)."""
        return replan_options(self.options, self.c_plan, self.setting.mechanics.c)

    def replan(self, t: NDArray[np.float64], ref: NDArray[np.float64], faces: tuple[str, ...],
               switches: tuple[float, ...], o: NDArray[np.float64]) -> PushPlan:
        """The rest of the task from the observed object ``o``: with the QP variant the sequence
        ``faces``, else a new search, both from a free start; with another its own condensing."""
        from tooltransfer.planner.planning.oe.qp_variant import condense_qp, condense_sequence
        from tooltransfer.planner.planning.switches import contact_fraction

        start = time.perf_counter()
        s_first = None
        if faces and faces[0] == self.face:  # the contact starts where the face touches the object
            s = contact_fraction(self.tool, faces[0], o, self.plant.tool_pose(), self.setting.radius)
            s_first = s * self.tool.face(faces[0]).length
        setting, opts = replan_setting(self.setting, o), self.replan_options()
        if not isinstance(opts, QPOptions):
            pp = self.clear_of_obstacles(self.oe.condense(t, ref, setting, self.target, opts))
        else:
            if faces:
                pp = self.clear_of_obstacles(condense_sequence(t, ref, setting, self.target, faces, switches, opts,
                                                               s_first=s_first, free_start=True))
                if pp.status != "solved":
                    self.log.append(f"re-plan of {' -> '.join(faces)} from {np.round(o, 4).tolist()}: {pp.reason}; "
                                    "new search")
            if not faces or pp.status != "solved":
                pp = self.clear_of_obstacles(condense_qp(t, ref, setting, self.target, opts, free_start=True))
        self.replan_times.append(time.perf_counter() - start)
        if pp.status == "solved" and not pp.pushes:
            return replace(pp, status="infeasible", reason="the re-plan has no push left")
        return pp

    def clear_of_obstacles(self, pp: PushPlan) -> PushPlan:
        """``pp``, or refused when the tool outline overlaps an obstacle along what the loop executes
        next (:func:`tooltransfer.planner.planning.oe.replan.refuse_tool_overlap`)."""
        return refuse_tool_overlap(self.tool, self.setting.obstacles, pp)

    def correction(self, o: NDArray[np.float64]) -> PushPlan:
        """A correction from ``o`` once the plan's path is used up: each way of
        :func:`tooltransfer.planner.planning.oe.correction.correction_references` in turn, fitted as its
        sequence, until one is solved (the last, a new search along the straight way)."""
        pp: PushPlan | None = None
        for way in correction_references(self.setting, self.options.friction_cone_fraction, o, self.target):
            pp = self.replan(way.t, way.ref, way.faces, way.switches, o)
            if pp.status == "solved":
                return pp
        assert pp is not None  # the straight way is always among the references
        return pp

    # ---------------------------------------------------------------- executing
    def leave(self, o: NDArray[np.float64], pose: NDArray[np.float64], face: str, start: NDArray[np.float64],
              change: bool, lead_in: NDArray[np.float64] | None = None) -> None:
        """From the contact at ``pose`` to ``face``'s contact pose ``start``: first straight back along
        the contact's normal from where the tool really is (a path planned from the observed object
        starts a camera error away, and a tool that moves sideways while touching drags the object
        along), then the switch (``change``) or the re-contact planned at the object observed again,
        joined where that path is clear of the object; with ``lead_in`` (the plan's own path, for an
        object where the plan puts it) that path instead."""
        assert self.face is not None
        back = pose[:2] - BACK_OFF * (rotation(float(pose[2])) @ self.tool.face(self.face).normal)
        self.move(np.vstack([pose[:2], back]))
        o = self.observe()
        if lead_in is not None and len(lead_in) >= 2:
            xy = lead_in
        else:
            planner = self.switch if change else self.recontact
            sw = planner(o, self.face, pose, face, start)
            if sw.status != "solved":
                what = f"switch {self.face} -> {face}" if change else f"re-contact of {face}"
                raise _Stop("failed", f"no {what} at {np.round(o, 4).tolist()} m: {sw.reason}")
            xy = sw.xy
        clear = [swept_clearance(self.tool, self.platform, xy[j:j + 1], o, self.setting.radius) for j in range(len(xy))]
        j = next((j for j, c in enumerate(clear) if c >= 0.5 * BACK_OFF), 0)
        self.move(np.vstack([back, xy[j:]]))
        if change:
            self.n_switches += 1
        else:
            self.n_recontacts += 1

    def push(self, p: Push, pp: PushPlan, o: NDArray[np.float64], k0: int, length: float,
             lead_in: NDArray[np.float64] | None = None) -> int:
        """Bring ``p``'s face to its contact pose at sample ``k0`` of the push (switch, re-contact or
        none; along ``lead_in`` (K, 2) [m], the plan's own path, when given), then push along ``p``
        for at most ``length`` [m] of object travel; returns the push sample reached."""
        pose = self.plant.tool_pose()
        start = p.tool_pose[k0]
        change = self.face is not None and self.face != p.face
        if change or np.hypot(*(pose[:2] - start[:2])) > SAME_POSE:
            self.leave(o, pose, p.face, start, change, lead_in)
        self.face = p.face
        xy = pp.object_xy[p.samples[k0:]]
        travel = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])
        k = int(np.searchsorted(travel, length, side="right")) - 1
        k = k0 + max(1, min(k, len(xy) - 1))
        here = self.plant.tool_pose()
        self.before = self.observe() if self.adapt else o
        self.move(np.vstack([here[:2], p.tool_pose[k0: k + 1, :2]]), record=self.adapt)
        self.n_pushes += 1
        return k

    # ---------------------------------------------------------------- adapting the model
    def learn(self, o: NDArray[np.float64]) -> None:
        """The last push chunk observed at its end ``o``: hand it to the model's adaptation
        (:class:`tooltransfer.tools.pushing.adaptation.Adaptation`), whose model, when it adapts one,
        the re-plans use from here."""
        if self.pending is None or self.before is None:
            return
        t, poses = self.pending
        self.pending = None
        mechanics, note = self.adaptation.learn(t, poses, self.before, o, self.setting.mechanics)
        if note:
            self.log.append(note)
        if mechanics is not None:
            self.setting = replace(self.setting, mechanics=mechanics)


class _Stop(ToolTransferError):
    def __init__(self, status: str, reason: str) -> None:
        self.status, self.reason = status, reason
        super().__init__(reason)


@dataclass(frozen=True)
class _Pace:
    """The closed loop's settings (see :func:`execute_closed_loop`): the target ``tolerance`` [m],
    the re-plan ``threshold`` [m] (the caller's, or three times the averaged camera noise if more),
    the longest ``chunk`` [m], the ``approach`` share near the end and the correction ``max_rounds``."""

    tolerance: float
    threshold: float
    chunk: float
    approach: float
    max_rounds: int


@dataclass
class _InForce:
    """The plan in force (first the plan itself) on its push-time axis from ``base`` [s], the push
    ``i`` and sample ``k`` reached, and the correction rounds taken so far."""

    plan: PushPlan
    base: float = 0.0
    i: int = 0
    k: int = 0
    rounds: int = 0

    def switch_to(self, plan: PushPlan, base: float) -> None:
        """Put ``plan`` in force from push-time ``base`` [s], at its first push's first sample."""
        self.plan, self.base, self.i, self.k = plan, base, 0, 0


def _plan_the_rest(loop: _Loop, ref: PlanReference, f: _InForce) -> bool:
    """A re-plan realised its first face only and the plan in force is used up short of its end:
    plan the rest from the observed object. Whether a plan was put in force."""
    current = f.plan
    partial = (f.i >= len(current.pushes) and bool(current.pushes)
               and current.pushes[-1].samples[-1] < current.t.size - 1)
    if not partial:
        return False
    o = loop.observe()
    tau = f.base + float(current.t[current.pushes[-1].samples[-1]] - current.t[0])
    if tau < ref.end - 0.05:
        t, r, faces, switches = ref.rest(tau, o, loop.target)
        pp = loop.replan(t, r, faces, switches, o)
        if pp.status == "solved":
            f.switch_to(pp, tau)
            return True
    return False


def _plan_done(loop: _Loop, ref: PlanReference, f: _InForce, pace: _Pace) -> tuple[str, str] | None:
    """The plan in force is done: is the object there (three observations averaged)? If not, a
    correction round. Returns the run's ``(status, reason)`` when it ends here, None when a
    correction is in force."""
    o = np.mean([loop.observe() for _ in range(3)], axis=0)
    if np.hypot(*(loop.target - o)) <= pace.tolerance:
        return "reached", ""
    f.rounds += 1
    if f.rounds > pace.max_rounds:
        return "rounds", f"{pace.max_rounds} correction rounds did not reach the target"
    d = float(np.hypot(*(loop.target - o)))
    pp = loop.correction(o)
    if pp.status != "solved":
        return "closest", f"no push brings the object closer from {np.round(o, 4).tolist()} m " \
            f"({1e3 * d:.1f} mm from the target): {pp.reason}"
    f.switch_to(pp, ref.end)
    return None


def _next_chunk(loop: _Loop, ref: PlanReference, f: _InForce, pace: _Pace) -> bool:
    """Observe, re-plan if the object strays more than the threshold from where the plan in force
    puts it, stage the last stretch for a mispredicting plant, then push one chunk. Whether the
    object was observed at the target (the run ends)."""
    p = f.plan.pushes[f.i]
    o = loop.observe()
    if loop.adapt:
        loop.learn(o)
    if np.hypot(*(loop.target - o)) <= pace.tolerance:
        return True
    expected = f.plan.object_xy[p.samples[f.k]]
    tau = f.base + float(f.plan.t[p.samples[f.k]] - f.plan.t[0])
    off = np.hypot(*(o - expected)) > pace.threshold
    if off and f.base >= ref.end:  # a correction in force, and the object strays from it: correct from here
        pp = loop.correction(o)
        if pp.status == "solved":
            f.switch_to(pp, ref.end)
            p = f.plan.pushes[0]
            loop.log.append(f"corrected again from {np.round(o, 4).tolist()} m: {' -> '.join(pp.faces)}")
    elif off and tau < ref.end - 0.05:
        t, r, faces, switches = ref.rest(tau, o, loop.target)
        pp = loop.replan(t, r, faces, switches, o)
        if pp.status == "solved":
            f.switch_to(pp, tau)
            p = f.plan.pushes[0]
        else:  # nothing better from here: the plan in force goes on
            loop.log.append(f"no re-plan from {np.round(o, 4).tolist()} m ({pp.reason}); the plan goes on")
    left = float(np.sum(np.linalg.norm(np.diff(f.plan.object_xy[p.samples[f.k]:], axis=0), axis=1)))
    if loop.adaptation.mispredicted >= 2 and not loop.staged and left < STAGE:
        # a plant the model mispredicts: the last stretch along the faces' normals, where the
        # object goes where it is aimed whatever its limit surface (an object pushed past the
        # target by a sideways push that fell short cannot be pushed back)
        loop.staged = True
        pp = loop.correction(o)
        if pp.status == "solved":
            f.switch_to(pp, ref.end)
            loop.log.append(f"staged the last {1e3 * left:.0f} mm along the faces' normals: "
                            f"{' -> '.join(pp.faces)}")
            return False
    length = pace.chunk if left > 2 * pace.chunk else max(pace.approach * left, 2e-4)
    lead = ref.lead_ins[f.i] if f.plan is ref.plan and f.k == 0 else None
    f.k = loop.push(p, f.plan, o, f.k, length, lead)
    loop.errors.append(loop.true_error())
    if f.k >= len(p.samples) - 1:
        f.i, f.k = f.i + 1, 0
    return False


def _report(status: str, reason: str, loop: _Loop | None, plant: Plant | None, tolerance: float,
            start: float) -> ClosedLoopReport:
    """The run's report (module docstring: the last look). ``start``: the run's ``perf_counter`` [s]."""
    err = loop.true_error() if loop is not None else float("nan")
    if loop is not None and status != "reached" and np.hypot(
            *(loop.target - np.mean([loop.observe() for _ in range(FINAL_LOOKS)], axis=0))) <= tolerance:
        status, reason = "reached", ""
    execution = getattr(plant, "execution", None) if plant is not None else None
    return ClosedLoopReport(
        status, reason, err, loop.n_pushes if loop else 0, loop.n_switches if loop else 0,
        loop.n_recontacts if loop else 0, len(loop.replan_times) if loop else 0,
        loop.replan_times if loop else [], loop.errors if loop else [], time.perf_counter() - start,
        execution, loop.log if loop else [], loop.setting.mechanics if loop else None,
        loop.adaptation.times if loop else [])


def execute_closed_loop(
    plan: Plan, plant: Plant | None = None, *, tolerance: float = 0.001, chunk: float = 0.015,
    approach: float = 0.6, max_rounds: int = 4, max_chunks: int = 120, frames: int = 10,
    replan_threshold: float = 0.001, adapt: bool = True, camera_noise: float = 0.0015, seed: int = 0,
    config: SimConfig | None = None,
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
    """
    if not isinstance(plan, Plan) or plan.status != "solved":
        raise InputError("plan", "a solved plan", getattr(plan, "status", type(plan).__name__))
    start = time.perf_counter()
    task = task_from_dict(plan.task, "plan.task")
    status, reason = "rounds", ""
    loop: _Loop | None = None
    try:
        loop = _Loop(plan, task, plant, frames, tolerance, adapt, camera_noise, seed, config)
        approach_m = np.asarray(plan.phase) == "approach"
        loop.move(plan.tool_pose[approach_m, :2])
        loop.face = plan.pushes[0].faces[0]
        ref = PlanReference.of(plan)
        f = _InForce(ref.plan)
        pace = _Pace(tolerance, max(replan_threshold, 3.0 * camera_noise / np.sqrt(frames)), chunk, approach,
                     max_rounds)
        for _ in range(max_chunks):
            if _plan_the_rest(loop, ref, f):
                continue
            if f.i >= len(f.plan.pushes):
                ended = _plan_done(loop, ref, f, pace)
                if ended is not None:
                    status, reason = ended
                    break
                continue
            if _next_chunk(loop, ref, f, pace):
                status = "reached"
                break
        else:
            status, reason = "rounds", f"{max_chunks} chunks did not reach the target"
    except _Stop as stop:
        status, reason = stop.status, stop.reason
    except Exception as exc:  # no exception escapes: a refused move ends the run with its reason
        status, reason = "failed", f"{type(exc).__name__}: {exc}"
    return _report(status, reason, loop, loop.plant if loop is not None else plant, tolerance, start)
