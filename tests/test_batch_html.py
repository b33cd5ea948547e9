"""The batch report as a page and as data: ``report.html`` written beside the CSV files and checked in
headless Chromium (no console error, every row drawn, filters, the task panel), the CSV files' unit
suffixes and full reasons, and ``tooltransfer.batch.load`` as a pandas DataFrame.

The store is written with the real store API; its rows are made up here (a few tasks, two variants,
reasons holding numbers, markup and template braces) so that what the page must show is known.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest
from browser import browser, console_errors, open_page
from rich.console import Console

from tooltransfer.planner.apps.batch.report import write_report
from tooltransfer.planner.apps.batch.store import ResultStore

REASONS = {
    "infeasible": "reach: the target is 12.345 mm outside the workspace [0.1, 0.2] of every face",
    "unknown": "no plan within 250 expansions; <script>alert(1)</script> {{ not a template }}",
}
N_TASKS = 6
VARIANTS = ("mapping/dmp", "qp/opt")


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[dict]]:
    """A store of N_TASKS tasks x VARIANTS and its report folder."""
    tmp = tmp_path_factory.mktemp("html_report")
    db = tmp / "r.sqlite"
    put = []
    with ResultStore(db) as store:
        store.set_meta(batch_name="html")
        store.add_tasks([{"task_id": f"t{i}", "idx": i, "tool": "slope", "n_obstacles": 1, "reach_margin": 0.01,
                          "task_json": json.dumps({"start": [0.04, 0.12], "target": [-0.05, 0.19],
                                                   "obstacles": [{"kind": "disc", "centre": [0.0, 0.15],
                                                                  "radius": 0.005}]})} for i in range(N_TASKS)])
        for i in range(N_TASKS):
            for v in VARIANTS:
                status = ("solved", "infeasible", "unknown")[(i + len(v)) % 3]
                row = {"task_id": f"t{i}", "variant": v, "tool": "slope", "status": status,
                       "reason": REASONS.get(status, ""), "time_total": 0.1 * (i + 1), "cone_violation_max": 0.002,
                       "goal_error": 2e-4 if status == "solved" else None}
                if status == "solved":
                    path = [[0.04, 0.12], [0.0, 0.16], [-0.05, 0.19]]
                    row["metrics_json"] = json.dumps({"qp_time_median": 0.003, "object_path": path})
                store.put(row)
                put.append(row)
    write_report(db, tmp / "rep", Console(file=io.StringIO(), width=200))
    return tmp, put


def test_csv_files_name_units_and_keep_reasons_whole(report: tuple[Path, list[dict]]) -> None:
    tmp, put = report
    with (tmp / "rep" / "results.csv").open() as fh:
        head = next(csv.reader(fh))
    assert {"time_total_s", "goal_error_m", "cone_violation_max_rad", "reach_margin_m", "n_obstacles", "status"} \
        <= set(head)
    assert "time_total" not in head and "goal_error" not in head
    with (tmp / "rep" / "summary.csv").open() as fh:
        head = next(csv.reader(fh))
    assert {"time_p50_s", "goal_error_max_m", "cone_violation_max_rad", "rate", "ci_low"} <= set(head)
    with (tmp / "rep" / "reasons.csv").open() as fh:
        reasons = list(csv.DictReader(fh))
    by = {(r["variant"], r["status"]): r for r in reasons}
    for (v, s), r in by.items():
        assert r["reason"] == REASONS[s]  # whole, numbers and all
        assert int(r["count"]) == sum(p["variant"] == v and p["status"] == s for p in put)


def test_load_gives_a_dataframe_with_units(report: tuple[Path, list[dict]]) -> None:
    pytest.importorskip("pandas", reason="pandas (the data extra) is not installed")
    import tooltransfer as tt

    tmp, put = report
    df = tt.batch.load(tmp / "r.sqlite")
    assert len(df) == len(put) == N_TASKS * len(VARIANTS)
    assert {"time_total_s", "goal_error_m", "valid", "metric_qp_time_median_s"} <= set(df.columns)
    assert sorted(df["status"].astype(str)) == sorted(p["status"] for p in put)
    assert df["time_total_s"].sum() == pytest.approx(sum(p["time_total"] for p in put))
    with pytest.raises(tt.InputError, match=r"missing\.sqlite"):
        tt.batch.load(tmp / "missing.sqlite")


def test_report_page_in_chromium(report: tuple[Path, list[dict]]) -> None:
    tmp, put = report
    page = tmp / "rep" / "report.html"
    text = page.read_text()
    assert "<script>alert(1)</script>" not in text and "&lt;script&gt;alert(1)&lt;/script&gt;" in text
    assert "http://" not in text.split("<body>")[0].replace("http://www.w3.org", "")  # nothing fetched at view time
    with browser() as d:
        open_page(d, page, "window.ttPanelTask")
        assert console_errors(d) == []
        assert d.execute_script("return document.querySelectorAll('#rows tbody tr').length") == len(put)
        assert d.execute_script("return [window.ttShown, window.ttDrawn]") == [len(put), len(put)]
        # the reasons are drawn whole (as text)
        cells = d.execute_script("return Array.from(document.querySelectorAll('#reasons td.reason'))"
                                 ".map(c => c.textContent)")
        assert set(cells) == set(REASONS.values())

        def filtered(script: str) -> list[str]:
            d.execute_script(script)
            return d.execute_script("return Array.from(document.querySelectorAll('#rows tbody tr'))"
                                    ".filter(r => r.style.display !== 'none').map(r => r.dataset.status + ' ' + "
                                    "r.dataset.variant)")

        sel = "var s = document.getElementById('f-{0}'); s.value = '{1}'; s.dispatchEvent(new Event('change'));"
        shown = filtered(sel.format("status", "infeasible"))
        assert sorted(shown) == sorted(f"infeasible {p['variant']}" for p in put if p["status"] == "infeasible")
        shown = filtered(sel.format("variant", "qp/opt"))
        assert sorted(shown) == sorted("infeasible qp/opt" for p in put
                                       if p["status"] == "infeasible" and p["variant"] == "qp/opt")
        shown = filtered(sel.format("status", "") + sel.format("variant", "") +
                         "var q = document.getElementById('f-text'); q.value = 'expansions';"
                         "q.dispatchEvent(new Event('input'));")
        assert len(shown) == sum(p["status"] == "unknown" for p in put) > 0
        # a click on a row draws its task: the obstacle, both pucks, the solved variants' paths
        d.execute_script("document.getElementById('f-text').value = '';"
                         "document.getElementById('f-text').dispatchEvent(new Event('input'));"
                         "document.querySelector('#rows tbody tr[data-task=\"t3\"]').click();")
        got = d.execute_script("var g = n => Bokeh.documents[0].get_model_by_name(n).data;"
                               "return [window.ttPanelTask, g('panel_discs').x.length, g('panel_pucks').x.length,"
                               "g('panel_paths').variant]")
        solved = [p["variant"] for p in put if p["task_id"] == "t3" and p["status"] == "solved"]
        assert got == ["t3", 1, 2, sorted(solved)]
        # sorting by time, descending after two clicks
        d.execute_script("var th = document.querySelectorAll('#rows thead th')[6]; th.click(); th.click();")
        first = d.execute_script("return document.querySelector('#rows tbody tr').dataset.task")
        assert first == f"t{N_TASKS - 1}"
        assert console_errors(d) == []
