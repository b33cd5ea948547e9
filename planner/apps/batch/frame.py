"""A batch's results as data: column names that carry their unit, and a pandas DataFrame.

Every CSV file ``batch report --out`` writes, and the DataFrame :func:`load` returns, name a
quantity with its SI unit as a suffix: ``time_total_s``, ``goal_error_m``, ``cone_violation_max_rad``
(:func:`with_unit`, from :mod:`tooltransfer.planner.common.metric_units`); counts, ratios, shares
and text keep their bare names. The values stay in SI units, as the store holds them.

:func:`load` reads a store read-only (:class:`~tooltransfer.planner.apps.batch.store.ResultStore`):
one row per task and variant, the store's columns and the task's difficulty measures, ``valid``
(:func:`~tooltransfer.planner.apps.batch.report.is_valid`), and every numeric plan metric of
``metrics_json`` that is not a column already, under ``metric_<name>[_<unit>]``. pandas is an
optional dependency (the ``data`` extra): without it :func:`load` raises an ``ImportError`` that
says what to install.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tooltransfer.planner.common.metric_units import column_unit

if TYPE_CHECKING:
    import pandas

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


def metric_columns(row: dict[str, Any]) -> dict[str, float]:
    """The numeric plan metrics of ``row["metrics_json"]`` that are not columns of ``row``, as
    ``metric_<name>[_<unit>]`` (SI values; the evidence and text left out)."""
    from tooltransfer.planner.common.metric_units import unit

    try:
        metrics = json.loads(row.get("metrics_json") or "{}")
    except ValueError:
        return {}
    if not isinstance(metrics, dict):
        return {}
    out: dict[str, float] = {}
    for k, v in metrics.items():
        if k in row or isinstance(v, bool) or not isinstance(v, int | float):
            continue
        out[with_unit(f"metric_{k}", unit(k) or "")] = float(v)
    return out


def load(db: str | Path) -> pandas.DataFrame:
    """The results of the batch store ``db`` as a pandas DataFrame (module docstring), in task and
    variant order; ``status`` and ``variant`` as categories.

    Raises:
        ModuleNotFoundError: pandas is not installed (``pip install "tooltransfer[data]"``).
        InputError: ``db`` is not a results file (naming it).
    """
    try:
        import pandas as pd
    except ImportError as exc:
        raise ModuleNotFoundError("tooltransfer.batch.load needs pandas: pip install \"tooltransfer[data]\" "
                                  "(or pip install pandas)", name="pandas") from exc
    from tooltransfer.errors import InputError
    from tooltransfer.planner.apps.batch.report import is_valid
    from tooltransfer.planner.apps.batch.store import RESULT_COLUMNS, ResultStore

    p = Path(db)
    if not p.is_file():
        raise InputError(f"db {p}", "an existing results file (written by tooltransfer batch run)",
                         "no such file" if not p.exists() else "not a regular file")
    if p.stat().st_size == 0:
        rows: list[dict[str, Any]] = []
    else:
        with ResultStore(p, readonly=True, field="db") as store:
            store.check_rows()
            rows = store.rows()
    full = [{**r, "valid": int(is_valid(r)), **metric_columns(r)} for r in rows]
    names = list(dict.fromkeys(k for r in full for k in r)) or [*RESULT_COLUMNS, "valid"]
    frame = pd.DataFrame(rows_with_units(full), columns=columns_with_units(names))
    for c in ("status", "variant", "tool"):
        if c in frame:
            frame[c] = frame[c].astype("category")
    return frame
