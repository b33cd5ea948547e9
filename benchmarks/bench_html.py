"""The HTML pages' sizes and speeds: ``report.html`` of a SYNTHETIC store of 1,000 tasks x 4 variants
(:mod:`synthetic_store`: made-up rows written with the real store API), its writing time and, in
headless Chromium (tests/browser.py), its load time and the filter's time over 4,000 rows; and
``tooltransfer view`` on a plan file (default: solved here from paper/transfer_tool2): the whole
process's wall time (median of 5) and the page's size.

    python benchmarks/bench_html.py [--tasks 1000] [--plan PLAN.json]
"""

from __future__ import annotations

import argparse
import io
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent / "tests")]

from browser import browser, console_errors, open_page  # noqa: E402
from rich.console import Console  # noqa: E402
from synthetic_store import synthetic_store  # noqa: E402

from tooltransfer.planner.apps.batch.report import write_report  # noqa: E402

QUERIES = ("infeasible", "synthetic-0042", "qp/opt", "reach: the target", "", "zzz", "timed out", "")


def bench_report(n_tasks: int, tmp: Path) -> None:
    db = synthetic_store(tmp / "synthetic.sqlite", n_tasks)
    t0, c0 = time.perf_counter(), time.process_time()
    write_report(db, tmp / "rep", Console(file=io.StringIO()))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    page = tmp / "rep" / "report.html"
    print(f"SYNTHETIC store, {n_tasks} tasks x 4 variants: batch report --out {wall:.2f} s wall, {cpu:.2f} s CPU "
          f"(CSV, PNG and report.html), report.html {page.stat().st_size / 1e6:.2f} MB")
    with browser() as d:
        t0 = time.perf_counter()
        open_page(d, page, "window.ttPanelTask", timeout=120)
        print(f"  Chromium: loaded and drawn in {time.perf_counter() - t0:.2f} s; console errors: {console_errors(d)}")
        times = []
        for _ in range(3):
            for q in QUERIES:
                ms, _ = d.execute_script(
                    "var e = document.getElementById('f-text'); e.value = arguments[0];"
                    "e.dispatchEvent(new Event('input')); return [window.ttFilterMs, window.ttShown];", q)
                times.append(ms)
        print(f"  filter over {4 * n_tasks} rows (text, {len(times)} times): median {statistics.median(times):.1f} ms, "
              f"max {max(times):.1f} ms")
        t0 = time.perf_counter()
        d.execute_script("var th = document.querySelectorAll('#rows thead th')[6]; th.click();")
        print(f"  sort by time: {1e3 * (time.perf_counter() - t0):.0f} ms (round trip)")


def bench_view(plan: Path | None, tmp: Path) -> None:
    exe = Path(sys.executable).with_name("tooltransfer")
    if plan is None:
        plan = tmp / "plan.json"
        subprocess.run([str(exe), "solve", "paper/transfer_tool2", "-o", str(plan)], check=True, capture_output=True)
    walls, cpus = [], []
    for _ in range(5):
        t0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([str(exe), "view", str(plan), "-o", str(tmp / "plan.html")], check=True, capture_output=True)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        walls.append(time.perf_counter() - t0)
        cpus.append(r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime)
    size = (tmp / "plan.html").stat().st_size
    print(f"tooltransfer view {plan.name}: whole process median {statistics.median(walls):.2f} s wall "
          f"(min {min(walls):.2f} s), {statistics.median(cpus):.2f} s CPU, of 5; page {size / 1e6:.2f} MB")
    print(f"load average: {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", type=int, default=1000)
    ap.add_argument("--plan", type=Path, default=None)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        bench_report(args.tasks, Path(tmp))
        bench_view(args.plan, Path(tmp))


if __name__ == "__main__":
    main()
