"""Column names that carry their unit: the CSV files of ``batch report --out`` and the DataFrame of
:func:`tooltransfer.planner.apps.batch.frame.load` name a quantity with its SI unit as a suffix
(``time_total_s``, ``goal_error_m``, ``cone_violation_max_rad``; from
:mod:`tooltransfer.planner.common.metric_units`); counts, ratios, shares and text keep their bare
names. The values stay in SI units, as the store holds them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from tooltransfer.planner.common.metric_units import column_unit

#: Units of the summary statistics (:class:`~tooltransfer.planner.apps.batch.report.GroupStats` fields)
#: that are quantities; the others are counts, rates, shares or text.
SUMMARY_UNITS: dict[str, str] = {
    "time_p50": "s", "time_p90": "s", "time_p99": "s", "time_max": "s",
    "cone_violation_max": "rad", "reach_violation_max": "m", "penetration_max": "m",
    "joint_limit_violation_max": "rad", "obstacle_clearance_min": "m", "goal_error_max": "m",
    "sim_final_error_median": "m", "ol_error_median": "m", "ol_error_p90": "m", "ol_wall_median": "s",
    "cl_error_median": "m", "cl_error_p90": "m", "cl_replan_time_max": "s", "cl_wall_median": "s",
}


def with_unit(name: str, unit: str | None = None) -> str:
    """``name`` with its SI unit as a suffix (``"time_total"`` -> ``"time_total_s"``): ``unit`` if
    given, else the store column's or plan metric's listed unit; bare for a count, a ratio, text or an
    unlisted name."""
    u = column_unit(name) if unit is None else unit
    return f"{name}_{u}" if u else name


def rows_with_units(rows: Iterable[dict[str, Any]], units: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """``rows`` with every key renamed by :func:`with_unit` (``units``: name to unit, for names that
    are not store columns, e.g. :data:`SUMMARY_UNITS`)."""
    def rename(k: str) -> str:
        return with_unit(k, units.get(k, "")) if units is not None else with_unit(k)

    return [{rename(k): v for k, v in r.items()} for r in rows]


def columns_with_units(names: Sequence[str], units: dict[str, str] | None = None) -> list[str]:
    """The column names ``names`` renamed as :func:`rows_with_units` does."""
    return [with_unit(k, units.get(k, "")) if units is not None else with_unit(k) for k in names]
