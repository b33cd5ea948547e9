"""The units of a plan's metrics and of an execution's summary, in one place.

A plan's metrics (``Plan.metrics``, the plan file's ``"metrics"`` with their units beside them in
``"metric_units"``, the batch store's columns) stay a ``dict[str, float]`` in SI units; :data:`UNITS`
says which unit each name is in, so a reader (the command line's tables, the plan file, the batch
report and its figures, the paper's report) does not guess it from the name. The batch store's
columns that are not plan metrics (a row's own measures, the executions' summaries, the tasks'
difficulty measures) have theirs in :data:`COLUMN_UNITS`. The QP's per-family constraint
violations ``violation_<family>`` are in the units of their family's rows and are not listed.

Lengths are shown in mm (:func:`shown`, :func:`display`); angles in rad, times in s (or ms where a
table asks for it), counts and ratios bare.
"""

from __future__ import annotations

from typing import Literal, get_args

Unit = Literal["m", "rad", "s", ""]
"""A metric's unit: metres, radians, seconds, or ``""`` for a count, a ratio or a factor."""
#: The unit strings (:data:`Unit`), as the plan file's ``metric_units`` holds them.
UNIT_NAMES: tuple[Unit, ...] = get_args(Unit)

UNITS: dict[str, Unit] = {
    # the object path (tooltransfer.planner.planning.oe.metrics.plan_metrics)
    "cone_violation_max": "rad",
    "friction_cone_margin_min": "rad",
    "contact_edge_margin_min": "m",
    "n_recontacts": "",
    "obstacle_clearance_min": "m",
    "margin": "m",
    "reach_violation_max": "m",
    "goal_error": "m",
    "deviation_mean": "m",
    "deviation_max": "m",
    "n_pushes": "",
    "path_length": "m",
    # the OE search
    "compute_time": "s",
    "n_qp": "",
    "qp_time_median": "s",
    "qp_time_max": "s",
    "final_candidates": "",
    # the whole plan (tooltransfer.planner.planning.solve)
    "safety_margin_used": "m",
    "mechanics_mu": "",
    "mechanics_c": "",
    "switch_clearance_min": "m",
    "recontact_clearance_min": "m",
    "n_switch_fallbacks": "",
    "switch_obstacle_clearance_min": "m",
    "switch_penetration_max": "m",
    "tool_obstacle_clearance_min": "m",
    "joint_limit_violation_max": "rad",
    "duration": "s",
    "stretch": "",
    "self_consistency_max": "m",
    "alternatives_tried": "",
    "time_skills": "s",
    "time_oe": "s",
    "time_switches_and_timing": "s",
    "time_replay": "s",
    "time_total": "s",
    "time_certify": "s",
    # a plan of the guided search (tooltransfer.planner.planning.oe.guided): the share of the friction
    # cone's half-angle it kept to, its search's step, its time, the expansions of a search that failed
    # and whether it ended on its budget (1) or with its space closed (0); on a plan the search did not
    # solve, its attempts and how many of them ended on their budget; 1 where the plan came from an
    # attempt at the widest share (oe.friction_cone_fraction_max, beyond 0.8: little margin for mu), or
    # from an attempt in the order of a distance field (oe.guided_field), or from the weighted search made
    # again where one on whole steps ended on its budget (guided_spent), or from the attempt on narrow
    # contact windows where a face is not held as a whole (guided_narrow), or from the last attempt, on 1 mm
    # windows with the tool nearer the obstacles (guided_close)
    "friction_cone_fraction": "",
    "guided_widest": "",
    "guided_field": "",
    "guided_spent": "",
    "guided_narrow": "",
    "guided_close": "",
    "guided_step": "m",
    "time_guided": "s",
    "guided_expansions": "",
    "guided_on_budget": "",
    "guided_attempts": "",
    "guided_attempts_on_budget": "",
    # the command line's summary of a plan and of its execution (tooltransfer.planner.apps.cli)
    "planning_time": "s",
    "open_loop_final_error": "m",
    "open_loop_tool_deviation": "m",
    "open_loop_tracking_error": "rad",
    "open_loop_wall_time": "s",
    "real_time_factor": "",
    "closed_loop_final_error": "m",
    "closed_loop_replan_time_median": "s",
    "closed_loop_wall_time": "s",
}

#: Units of the batch store's columns (``tooltransfer.planner.apps.batch.store.RESULT_COLUMNS`` and the tasks'
#: ``TASK_COLUMNS``) that are not plan metrics: each row's own measures, the open- and closed-loop
#: executions' summaries (``sim_*`` the schema-1 names of the open loop's) and the tasks' difficulty
#: measures. No name is in both tables.
COLUMN_UNITS: dict[str, Unit] = {
    # a row's own measures (tooltransfer.planner.apps.batch.execute.execute_job)
    "cpu_time": "s",
    "penetration_max": "m",
    "n_switches": "",
    "wall_time": "s",
    "started_at": "s",
    "finished_at": "s",
    # the open loop's execution (tooltransfer.planner.apps.batch.execute.open_loop)
    "open_loop_error": "m",
    "sim_final_error": "m",
    "sim_tool_deviation": "m",
    "sim_wall_time": "s",
    "sim_success": "",
    # the closed loop's execution (tooltransfer.planner.apps.batch.execute.closed_loop)
    "closed_loop_error": "m",
    "closed_loop_pushes": "",
    "closed_loop_switches": "",
    "closed_loop_recontacts": "",
    "closed_loop_replans": "",
    "closed_loop_replan_time_max": "s",
    "closed_loop_seed": "",
    # the tasks' difficulty measures (tooltransfer.planner.apps.batch.generate)
    "idx": "",
    "n_obstacles": "",
    "start_reach": "m",
    "target_reach": "m",
    "reach_margin": "m",
    "distance": "m",
}

#: The units a value may be shown in: each with the SI unit it scales and the factor from SI to it.
SCALED: dict[str, tuple[Unit, float]] = {
    "mm": ("m", 1e3), "m": ("m", 1.0), "rad": ("rad", 1.0), "s": ("s", 1.0), "ms": ("s", 1e3), "": ("", 1.0),
}


def unit(name: str) -> Unit | None:
    """The unit of metric ``name``, or None when it is not listed (:data:`UNITS`)."""
    return UNITS.get(name)


def column_unit(name: str) -> Unit | None:
    """The unit of the batch store's column ``name``: a plan metric's (:data:`UNITS`) or one of
    :data:`COLUMN_UNITS`; None when it has none listed (a text column, a QP family's violation)."""
    return UNITS.get(name, COLUMN_UNITS.get(name))


def display(name: str, shown_as: str | None = None) -> tuple[str, float]:
    """The unit the metric or column ``name`` is shown in and the factor from its SI value to it:
    a length in mm, an angle in rad, a time in s, a count bare (``""``, 1); ``shown_as`` picks
    another unit of the same quantity (``"ms"`` for a time).

    Raises:
        KeyError: ``name`` is in neither :data:`UNITS` nor :data:`COLUMN_UNITS`.
        ValueError: ``shown_as`` is not a unit of ``name``'s quantity (:data:`SCALED`).
    """
    si = column_unit(name)
    if si is None:
        raise KeyError(f"no unit listed for {name!r} (tooltransfer.planner.common.metric_units)")
    if shown_as is None:
        shown_as = "mm" if si == "m" else si
    base, factor = SCALED.get(shown_as, (None, 0.0))
    if base != si:
        raise ValueError(f"{name!r} is in {si!r}; it cannot be shown in {shown_as!r}")
    return shown_as, factor


def label(text: str, name: str, shown_as: str | None = None) -> str:
    """``text`` with the unit ``name`` is shown in (:func:`display`) in brackets: ``"goal err [mm]"``;
    ``text`` alone for a count or a ratio."""
    u, _ = display(name, shown_as)
    return f"{text} [{u}]" if u else text


def shown(name: str, value: float) -> tuple[str, str]:
    """The label and the text of metric ``name`` at ``value`` (SI) for a table: a length in mm
    (``"goal_error [mm]"``), an angle in rad, a time in s, anything else bare; 4 significant digits."""
    u = unit(name)
    if u == "m":
        return f"{name} [mm]", f"{1e3 * value:.4g}"
    if u in ("rad", "s"):
        return f"{name} [{u}]", f"{value:.4g}"
    return name, f"{value:.4g}"


__all__ = ["COLUMN_UNITS", "SCALED", "UNITS", "UNIT_NAMES", "Unit", "column_unit", "display", "label", "shown", "unit"]
