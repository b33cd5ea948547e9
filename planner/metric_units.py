"""The units of a plan's metrics and of an execution's summary, in one place.

A plan's metrics (``Plan.metrics``, the plan file's ``"metrics"``, the batch store's columns) stay a
``dict[str, float]`` in SI units; :data:`UNITS` says which unit each name is in, so a reader (the
command line's tables, a report) does not guess it from the name. The QP's per-family constraint
violations ``violation_<family>`` are in the units of their family's rows and are not listed.

Lengths are shown in mm (:func:`shown`); angles in rad, times in s, counts and ratios bare.
"""

from __future__ import annotations

from typing import Literal

Unit = Literal["m", "rad", "s", ""]
"""A metric's unit: metres, radians, seconds, or ``""`` for a count, a ratio or a factor."""

UNITS: dict[str, Unit] = {
    # the object path (tooltransfer.planner.oe.metrics.plan_metrics)
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
    # the whole plan (tooltransfer.planner.solve)
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
    # the command line's summary of a plan and of its execution (tooltransfer.planner.cli)
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


def unit(name: str) -> Unit | None:
    """The unit of metric ``name``, or None when it is not listed (:data:`UNITS`)."""
    return UNITS.get(name)


def shown(name: str, value: float) -> tuple[str, str]:
    """The label and the text of metric ``name`` at ``value`` (SI) for a table: a length in mm
    (``"goal_error [mm]"``), an angle in rad, a time in s, anything else bare; 4 significant digits."""
    u = unit(name)
    if u == "m":
        return f"{name} [mm]", f"{1e3 * value:.4g}"
    if u in ("rad", "s"):
        return f"{name} [{u}]", f"{value:.4g}"
    return name, f"{value:.4g}"


__all__ = ["UNITS", "Unit", "shown", "unit"]
