"""The planner end to end: a task in, a plan out (``tooltransfer.planner.planning.solve``).

Stages (each timed in the plan's metrics): skills (the universal OE skill learned from the task's
dataset, cached in memory by the dataset's content hash), the setting (tool, platform, object, push
mechanics, obstacles, margin: :mod:`tooltransfer.planner.planning.setting`), OE condensing with the chosen variant
(:mod:`tooltransfer.planner.planning.variant_registry`; pushes realised
by the inverse push model, :mod:`tooltransfer.planner.planning.oe.contacts`), a switch between consecutive pushes of
different faces and a re-contact between pieces of one face, approach and retreat, timing under the
tool's speed and acceleration limits, inverse kinematics of the whole tool path (joint limits
checked), and the checks: the shared OE metrics on the dense object path, the switches' clearances,
the tool body against the obstacles at every sample, the joint-limit violation, and the plan's
self-consistency: the forward push model (:mod:`tooltransfer.tools.pushing.forward`) replays the whole planned
tool path from the start and must reproduce the planned object path within
``oe.self_consistency_tol`` (a switch that knocks the object, a push the mechanics would not
deliver, fail here with the time and place).

Switch variants (:data:`tooltransfer.planner.planning.variant_registry.SS_VARIANTS`, planners in
:mod:`tooltransfer.planner.planning.switches`): ``arch`` (the geometric reference of
:mod:`tooltransfer.planner.planning.ss.arch_variant`), ``dmp`` (the SS skill recombined, eq. 18; its penetration
is reported, not avoided) and ``opt`` (the CasADi NLP, non-penetrating, checked with shapely; where it
finds no path, the ``arch`` one).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Generator, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
import shapely

from tooltransfer.errors import InputError
from tooltransfer.planner.common.metric_units import UNITS
from tooltransfer.planner.planning.assemble import SwitchFailed, assemble
from tooltransfer.planner.planning.oe.generalize import generalize
from tooltransfer.planner.planning.oe.mapping_variant import MappingOptions
from tooltransfer.planner.planning.oe.metrics import CONE_BOUND
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.plan import Plan, Segment
from tooltransfer.planner.planning.recontact import recontact_planner
from tooltransfer.planner.planning.setting import Setting, setting_from_task, task_skills
from tooltransfer.planner.planning.switches import with_fallback
from tooltransfer.planner.planning.tool_clearance import TOOL_MARGIN, tool_obstacle_clearance
from tooltransfer.planner.planning.variant_registry import needs_ss_skill, oe_variant, switch_planner
from tooltransfer.planner.planning.verdicts.decide import Sought, attach_verdict, seek_certificate
from tooltransfer.problems.task import Task, resolve, task_origin
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.pushing.forward import simulate


def _as_loaded(task: Task, task_path: str | Path) -> dict[str, Any]:
    """The task as JSON data with its skills path resolved (absolute), so a plan file stands alone."""
    data = task.model_dump(mode="json")
    for key in ("dataset", "file"):
        if data["skills"].get(key) is not None:
            data["skills"][key] = str(resolve(task_path, data["skills"][key]).resolve())
    return data


def qp_options(task: Task) -> QPOptions:
    """The ``qp`` variant's options from the task's ``oe`` section (:meth:`QPOptions.from_task`)."""
    return QPOptions.from_task(task.oe)


def mapping_options(task: Task) -> MappingOptions:
    """The ``mapping`` variant's options from the task's ``oe`` section (:meth:`MappingOptions.from_task`)."""
    return MappingOptions.from_task(task.oe)


def solve(task: Task, task_path: str | Path | None = None, *, budget: float = 1.0,
          on_slow: Callable[[], None] | None = None) -> Plan:
    """Plan ``task`` and give it a verdict (:attr:`Plan.verdict`): ``"solved"`` only when every hard
    check holds (the variant's condensing, then its guided search where it has one and the
    condensing's candidates fail); where no plan is found, ``"infeasible"`` with a certificate that no plan
    exists under the rules it states (:mod:`tooltransfer.planner.planning.verdicts`), else
    ``"unknown"`` with what was searched (``"violated"`` keeps a plan that breaks a hard check). The
    plan's ``evidence`` holds the certificate or the search's account. Where the variant has a guided
    search, the certificate is looked for before it: a task it proves infeasible is not searched
    further (its metric ``time_certify`` is that look's, also on a plan the guided search then solves).

    Relative paths in the task are relative to ``task_path``'s folder, by default the folder of the file
    the task was loaded from (:func:`~tooltransfer.problems.task.load_task`; the working folder for a task
    built in code). ``budget`` (>= 1) scales what the search and the certificate may spend (the guided
    search's expansions, ``oe.guided_budget``, and the certificate's block updates): ``batch run --retry
    unknown --budget K`` gives the undecided tasks more. ``on_slow`` is called (once, without
    arguments) where the variant's condensing found no plan and the slower stages begin (the certificate,
    then the guided search): a tool choice stops only candidates that have called it."""
    check_budget(budget)
    plan, setting, sought = _search(task, task_path, budget, on_slow)
    return attach_verdict(plan, setting, np.array(task.start), np.array(task.target), budget=budget, sought=sought)


def check_budget(budget: object, field: str = "budget") -> float:
    """``budget`` as a float when it is a number >= 1 (:func:`solve`'s), else :class:`InputError` naming
    ``field`` (``--budget`` on the command line)."""
    if not (isinstance(budget, int | float) and math.isfinite(budget) and budget >= 1.0):
        raise InputError(field, "a number >= 1 (the search's and the certificate's budgets are multiplied by it)",
                         repr(budget))
    return float(budget)


def _search(task: Task, task_path: str | Path | None, budget: float = 1.0,
            on_slow: Callable[[], None] | None = None) -> tuple[Plan, Setting, Sought | None]:
    """The planner's search (module docstring): the plan, or the best failure, the world it used and,
    where the variant has a guided search, the certificate looked for before it (a task proved
    infeasible is not searched further; a sound certificate leaves nothing to find)."""
    task_path = task_origin(task, task_path)
    stages: dict[str, float] = {}
    start = clock = time.perf_counter()

    def lap(name: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        stages[f"time_{name}"] = now - clock
        clock = now

    skills = task_skills(task, task_path, need_ss=needs_ss_skill(task.variants.ss))
    lap("skills")
    setting = setting_from_task(task, skills, task_path)
    desc = setting.describe()
    desc["object"].update(start=list(task.start), goal=list(task.target))
    base = {"variant": {"oe": task.variants.oe, "ss": task.variants.ss}, "task": _as_loaded(task, task_path),
            **desc}
    t, x, _ = generalize(skills.oe.dmp, np.array(task.start), np.array(task.target))
    target = np.array(task.target)
    oe = oe_variant(task.variants.oe)
    options = oe.options_from_task(task.oe)
    if budget != 1.0 and "guided_budget" in type(options).model_fields:
        options = options.model_copy(update={"guided_budget": round(options.guided_budget * budget)})
    push_plan = oe.condense(t, x, setting, target, options)
    lap("oe")
    switch = switch_planner(task.variants.ss, setting, skills.ss, task.ss)
    recontact = with_fallback(recontact_planner(setting), switch, "switch")
    if push_plan.status != "solved":
        plan = Plan(status="infeasible", reason=push_plan.reason, metrics=stages, **base)
    else:
        plan = _candidates(task, setting, push_plan, switch, recontact, stages, base, start)
    if plan.status != "solved" and on_slow is not None:
        on_slow()
    sought = None
    if plan.status != "solved" and oe.guided is not None:
        sought = seek_certificate(setting, np.array(task.start), target, budget=budget)
        if sought.cert is None:
            plan = _guided(task, setting, oe.guided(t, x, setting, target, options), plan, switch, recontact, base,
                           start)
            plan.metrics["time_certify"] = sought.spent
    return plan, setting, sought


def _guided(task: Task, setting: Setting, attempts: Generator[Any, Any, None], failed: Plan, switch: Any,
            recontact: Any, base: dict[str, Any], start: float) -> Plan:
    """The first whole plan of the variant's guided search (its push plans, one per attempt) that passes
    every check, where the scored candidates left ``failed``; else ``failed`` with each attempt's reason
    added. A switch that found no tool path is sent back to the search (it may avoid it). A plan whose
    tool comes within :data:`GUIDED_ROOM` of an obstacle is kept only when no later attempt gives one
    with more room (the closed loop's corrections need some), but for the attempts at the widest share of
    the friction cone (metric ``guided_widest``) after a plan at a narrower one: they would spend the
    margin kept for an error in ``mu``. The plan kept is sent back to the search, which then makes none of its
    last attempts (``guide``, ``spent`` and ``narrow``,
    :func:`~tooltransfer.planner.planning.oe.guided.guided_plans`): they come after every other and are there for
    tasks with no plan at all."""
    clock = time.perf_counter()
    whys: list[str] = []
    n_tried = n_on_budget = 0  # the attempts, and those whose search ended on its budget (not its space)
    # sent back: a switch refused (the search may avoid that change of face there), or the plan kept
    sent: SwitchFailed | Plan | None = None
    tight: Plan | None = None  # the first solved plan with little room, if no roomier one comes
    while True:
        try:
            guided = attempts.send(sent)
        except StopIteration:
            break
        sent = None
        if tight is not None and guided.metrics.get("guided_widest") and not tight.metrics.get("guided_widest"):
            break  # a plan at the widest share of the friction cone would trade its margin for the room
        n_tried += 1
        n_on_budget += int(guided.metrics.get("guided_on_budget", 0.0) > 0.0)
        if guided.status == "solved":
            stages = {k: v for k, v in failed.metrics.items() if k in ("time_skills", "time_oe")}
            switches: list[SwitchFailed] = []
            plan = _complete(task, setting, guided, switch, recontact, stages, base, switches)
            sent = switches[0] if switches else None
            if plan.status == "solved":
                plan.metrics["time_guided"] = time.perf_counter() - clock
                plan.metrics["time_total"] = time.perf_counter() - start
                tried = float(failed.metrics.get("alternatives_tried", 0.0))
                plan.metrics["alternatives_tried"] = tried + 1.0 + len(whys)
                room = min(plan.metrics["tool_obstacle_clearance_min"], plan.metrics["switch_obstacle_clearance_min"])
                if room >= GUIDED_ROOM:
                    return plan
                tight = plan if tight is None else tight
                sent = tight  # (a plan is kept: no last attempts for one)
                whys.append(f"a plan whose tool passes {room * 1e3:.2f} mm from an obstacle (kept unless one "
                            f"with {GUIDED_ROOM * 1e3:g} mm comes)")
                continue
            whys.append(plan.reason)
        else:
            whys.append(guided.reason)
    if tight is not None:
        tight.metrics["time_guided"] = time.perf_counter() - clock
        tight.metrics["time_total"] = time.perf_counter() - start
        return tight
    metrics = {**failed.metrics, "time_guided": time.perf_counter() - clock, "guided_attempts": float(n_tried),
               "guided_attempts_on_budget": float(n_on_budget)}
    if "time_total" in failed.metrics:  # the candidates' (a first one without alternatives, a violated one)
        metrics["time_total"] = failed.metrics["time_total"] + metrics["time_guided"]
    return replace(failed, metrics=metrics, reason=f"{failed.reason}; the guided search: {'; then '.join(whys)}")


#: Room [m] between the tool and the obstacles a guided plan should leave for the closed loop's
#: corrections (its safety envelope refuses commands within 0.25 mm of an obstacle).
GUIDED_ROOM = 0.001


def _candidates(task: Task, setting: Setting, push_plan: Any, switch: Any, recontact: Any,
                stages: dict[str, float], base: dict[str, Any], start: float) -> Plan:
    """The first candidate push plan (``push_plan``, then those it hands out) that makes a whole plan
    passing every check; else the first that broke a hard check, or the last failure."""
    reasons: list[str] = []
    violated: Plan | None = None  # the first whole plan that breaks a hard check (kept if nothing solves)
    while True:  # the push plan, then the next candidates it hands out while a later stage fails
        plan = _complete(task, setting, push_plan, switch, recontact, stages, base)
        if plan.status == "violated" and violated is None:
            violated = plan
        if plan.status == "solved" or push_plan.next_best is None:
            break
        reasons.append(plan.reason)
        push_plan = push_plan.next_best()
        if push_plan.status != "solved":
            break
    if plan.status != "solved" and violated is not None:
        plan = violated
    elif plan.status != "solved" and reasons:
        more = f" (and {len(reasons)} other push sequence(s) before it: {reasons[0]})" if reasons else ""
        why = plan.reason if plan.reason else push_plan.reason
        return Plan(status="infeasible", reason=why + more, metrics=plan.metrics or stages, **base)
    plan.metrics["time_total"] = time.perf_counter() - start
    plan.metrics["alternatives_tried"] = float(len(reasons))
    return plan


def _push_collision(tool: Tool, push_plan: Any, obstacles: Sequence[Disc | shapely.Polygon]) -> str:
    """Where the tool outline, at the poses of ``push_plan``'s pushes (before any switch is planned),
    overlaps an obstacle in the first push where it does (its first sample there with the lowest-numbered
    obstacle it overlaps), as a reason; empty where it overlaps none."""
    for p in push_plan.pushes:
        near = tool_obstacle_clearance(tool, p.tool_pose, obstacles)
        if near.distance <= 0.0:
            return (f"tool-obstacle collision: the tool outline overlaps obstacles[{near.obstacle}] at "
                    f"t = {push_plan.t[p.samples[near.sample]]:.2f} s (push of {p.face!r}; tool at "
                    f"{np.round(p.tool_pose[near.sample, :2], 4).tolist()} m)")
    return ""


def _complete(task: Task, setting: Setting, push_plan: Any, switch: Any, recontact: Any,
              stages: dict[str, float], base: dict[str, Any],
              failed_switches: list[SwitchFailed] | None = None) -> Plan:
    """A solved push plan made a whole plan (switches, timing, joints) and checked (module docstring);
    a switch that finds no tool path is added to ``failed_switches`` where given."""
    clock = time.perf_counter()
    missing = [k for k in PUSH_PLAN_MEASURES if k not in push_plan.metrics]
    if missing:  # a hard check with nothing to check is not a check that holds
        return Plan(status="infeasible", metrics={**push_plan.metrics, **stages}, **base,
                    reason=f"the push plan carries no {', '.join(missing)}: its hard checks cannot be made")
    tool, platform, radius = setting.tool, setting.platform, setting.radius
    obstacles = list(setting.obstacles)
    try:
        motion = assemble(push_plan, tool, platform, switch, recontact, v_max=task.timing.max_tool_speed,
                          a_max=task.timing.max_tool_accel, approach_distance=task.timing.approach_distance,
                          obstacles=obstacles, puck_radius=radius)
    except SwitchFailed as exc:
        if failed_switches is not None:
            failed_switches.append(exc)
        hit = _push_collision(tool, push_plan, obstacles)  # a push that cannot be made is the first cause
        why = f"{hit}; its switch {exc.face_a} -> {exc.face_b} failed too: {exc.reason}" if hit else str(exc)
        return Plan(status="infeasible", reason=why, metrics={**push_plan.metrics, **stages}, **base)
    stages = {**stages, "time_switches_and_timing": time.perf_counter() - clock}
    metrics = {**push_plan.metrics, **stages, "safety_margin_used": setting.margin,
               "mechanics_mu": setting.mechanics.mu, "mechanics_c": setting.mechanics.c}
    sws = [sw for fa, fb, *_, sw in motion.switches if fa != fb]
    recs = [sw for fa, fb, *_, sw in motion.switches if fa == fb]
    metrics["switch_clearance_min"] = min((sw.object_clearance for sw in sws), default=float("inf"))
    metrics["recontact_clearance_min"] = min((sw.object_clearance for sw in recs), default=float("inf"))
    metrics["n_switch_fallbacks"] = float(sum(sw.fallback for *_, sw in motion.switches))
    sws = [sw for *_, sw in motion.switches]
    metrics["switch_obstacle_clearance_min"] = min((sw.obstacle_clearance for sw in sws), default=float("inf"))
    metrics["switch_penetration_max"] = max((sw.max_penetration for sw in sws), default=0.0)
    near = tool_obstacle_clearance(tool, motion.tool_pose, obstacles)
    metrics["tool_obstacle_clearance_min"] = near.distance
    metrics["joint_limit_violation_max"] = float(motion.joint_violation.max())
    metrics["duration"] = float(motion.t[-1])
    metrics["stretch"] = motion.stretch
    if not np.isfinite(metrics["joint_limit_violation_max"]) or metrics["joint_limit_violation_max"] > 1e-9:
        bad = int(np.argmax(motion.joint_violation))
        where = (f"at t = {motion.t[bad]:.2f} s ({motion.phase[bad]}; tool at "
                 f"{np.round(motion.tool_pose[bad, :2], 4).tolist()} m)")
        why = ("the tool path leaves the Omni's reach" if not np.isfinite(motion.joint_violation[bad])
               else f"the tool path leaves the Omni's joint limits by {motion.joint_violation[bad]:.3g} rad")
        return Plan(status="infeasible", metrics=metrics, **base, reason=f"joint limits: {why} {where}")
    if near.distance <= 0.0:
        k = near.sample
        return Plan(status="infeasible", metrics=metrics, **base,
                    reason=f"tool-obstacle collision: the tool outline overlaps obstacles[{near.obstacle}] at "
                           f"t = {motion.t[k]:.2f} s ({motion.phase[k]}; tool at "
                           f"{np.round(motion.tool_pose[k, :2], 4).tolist()} m)")
    t_replay = time.perf_counter()
    replay = simulate(tool, motion.tool_pose, np.array(task.start), radius, setting.mechanics)
    off = np.linalg.norm(replay.object_xy - motion.object_xy, axis=1)
    metrics["self_consistency_max"] = float(off.max())
    metrics["time_replay"] = time.perf_counter() - t_replay
    if off.max() > task.oe.self_consistency_tol:
        k = int(np.argmax(off > task.oe.self_consistency_tol))
        return Plan(status="infeasible", metrics=metrics, **base,
                    reason=f"self-consistency: replayed through the push model, the planned tool path moves the "
                           f"object {1e3 * off.max():.2f} mm off the planned path (from t = {motion.t[k]:.2f} s, "
                           f"{motion.phase[k]}; object planned at {np.round(motion.object_xy[k], 4).tolist()} m)")
    pushes = tuple(Segment("push", a, b, (f,), {"direction": d}) for f, a, b, d in motion.pushes)
    switches = tuple(Segment("switch", a, b, (fa, fb), {"min_clearance": float(sw.object_clearance),
                                                         "penetration": float(sw.object_penetration)})
                     for fa, fb, a, b, sw in motion.switches)
    broken = hard_check_failures(metrics, task.oe.self_consistency_tol)
    status: Literal["solved", "violated"] = "violated" if broken else "solved"
    reason = "hard checks violated: " + "; ".join(broken) if broken else ""
    return Plan(status=status, reason=reason, t=motion.t, object_xy=motion.object_xy, tool_pose=motion.tool_pose,
                joints=motion.joints, phase=motion.phase, face=motion.face, pushes=pushes, switches=switches,
                metrics=metrics, **base)


#: The measures of the object path every solved push plan carries
#: (:func:`tooltransfer.planner.planning.oe.metrics.plan_metrics`): a plan without one is not checked, so not solved.
PUSH_PLAN_MEASURES = ("cone_violation_max", "friction_cone_margin_min", "contact_edge_margin_min",
                      "reach_violation_max", "goal_error", "obstacle_clearance_min")

#: The hard checks of a whole plan (:func:`hard_check_failures`): family, metric, bound (in the metric's
#: unit), sense (``"max"``: the metric may not exceed the bound; ``"min"``: it may not fall below it), unit
#: (:data:`tooltransfer.planner.common.metric_units.UNITS`). A plan that breaks one is ``violated`` (the paper's
#: mapping variant guarantees none of them), still written and compared.
_HARD_BOUNDS: tuple[tuple[str, str, float, str], ...] = (
    ("cone", "cone_violation_max", CONE_BOUND, "max"),
    ("friction cone", "friction_cone_margin_min", -1e-6, "min"),
    ("contact edge", "contact_edge_margin_min", -1e-6, "min"),
    ("switch penetration", "switch_penetration_max", 1e-5, "max"),
    ("reach", "reach_violation_max", 1e-3, "max"),
    ("tool-obstacle clearance", "tool_obstacle_clearance_min", TOOL_MARGIN, "min"),
    ("switch-obstacle clearance", "switch_obstacle_clearance_min", TOOL_MARGIN, "min"),
    ("joint limits", "joint_limit_violation_max", 1e-9, "max"),
    ("goal", "goal_error", 1e-4, "max"),
)
HARD_CHECKS: tuple[tuple[str, str, float, str, str], ...] = tuple(
    (family, key, bound, sense, UNITS[key]) for family, key, bound, sense in _HARD_BOUNDS)


def hard_check_failures(metrics: dict[str, float], self_consistency_tol: float = 1e-4) -> list[str]:
    """The hard checks (:data:`HARD_CHECKS`, the safety margin: ``obstacle_clearance_min`` at least
    ``safety_margin_used``, and ``self_consistency_max`` within ``self_consistency_tol``) that
    ``metrics`` break, each as ``"family (metric value > bound)"``; empty when every one holds. A
    missing or NaN metric (e.g. the friction-cone margin of a plan without pushes) is not checked."""
    checks = [*HARD_CHECKS,
              ("self-consistency", "self_consistency_max", self_consistency_tol, "max", UNITS["self_consistency_max"])]
    margin = metrics.get("safety_margin_used")
    if margin is not None:
        checks.append(("safety margin", "obstacle_clearance_min", float(margin) - 1e-5, "min", "m"))
    out = []
    for family, key, bound, sense, unit in checks:
        v = metrics.get(key)
        if v is None or np.isnan(v):
            continue
        v = float(v)
        ok = v <= bound if sense == "max" else v >= bound
        if not ok:
            out.append(f"{family} ({key} {v:.4g} {unit} {'>' if sense == 'max' else '<'} {bound:.4g})")
    return out
