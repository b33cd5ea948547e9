"""A batch's results as data: column names that carry their unit, and a pandas DataFrame.

Every CSV file ``batch report --out`` writes, and the DataFrame :func:`load` returns, name a
quantity with its SI unit as a suffix: ``time_total_s``, ``goal_error_m``, ``cone_violation_max_rad``
(:mod:`tooltransfer.planner.apps.batch.units`); counts, ratios, shares and text keep their bare names.
The values stay in SI units, as the store holds them.

:func:`load` reads a store read-only (:class:`~tooltransfer.planner.apps.batch.store.ResultStore`):
one row per task and variant, the store's columns and the task's difficulty measures, ``valid``
(:func:`~tooltransfer.planner.apps.batch.report.is_valid`), and every numeric plan metric of
``metrics_json`` that is not a column already, under ``metric_<name>[_<unit>]``. pandas is an
optional dependency (the ``data`` extra): without it :func:`load` raises an ``ImportError`` that
says what to install.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tooltransfer.planner.apps.batch.units import columns_with_units, rows_with_units, with_unit

if TYPE_CHECKING:
    import pandas


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
