"""Batch feasibility studies: many generated tasks, every variant, in parallel, into SQLite.

- :mod:`tooltransfer.planner.apps.batch.spec`: batch files (``tooltransfer.batch/1``, pydantic);
- :mod:`tooltransfer.planner.apps.batch.generate`: deterministic random tasks, each a valid task file;
- :mod:`tooltransfer.planner.apps.batch.sandbox` and :mod:`tooltransfer.planner.apps.batch.worker`: each job isolated in
a long-lived
  child process with a timeout (hangs, crashes and exceptions become rows);
- :mod:`tooltransfer.planner.apps.batch.executors`: a process pool or Dask distributed, one code path;
- :mod:`tooltransfer.planner.apps.batch.store`: the SQLite store (WAL, one row per task and variant, resumable);
- :mod:`tooltransfer.planner.apps.batch.jobs`: the jobs of each task and variant, generated as the run goes;
- :mod:`tooltransfer.planner.apps.batch.store_settings`: a store tied to its batch and settings;
- :mod:`tooltransfer.planner.apps.batch.runner`: submit, store as each finishes, progress, Ctrl-C;
- :mod:`tooltransfer.planner.apps.batch.report` and :mod:`tooltransfer.planner.apps.batch.figures`: tables, CSV,
  figures; :mod:`tooltransfer.planner.apps.batch.html_report`: ``report.html``;
- :mod:`tooltransfer.planner.apps.batch.frame`: :func:`load`, the results as a pandas DataFrame
  (``tooltransfer.batch.load``); :mod:`tooltransfer.planner.apps.batch.units`: the unit-suffixed
  column names of the CSV files;
- :mod:`tooltransfer.planner.apps.batch.commands`: ``tooltransfer batch generate|run|report|schema``.

Scripts that call :func:`run_batch` must guard their entry point with ``if __name__ ==
"__main__":`` (the process pool spawns its workers, which import the main module).
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_EXPORTS = {
    "BatchSpec": "spec", "load_batch": "spec", "GeneratedTask": "generate", "generate_tasks": "generate",
    "write_tasks": "generate", "ResultStore": "store", "RunSummary": "runner", "run_batch": "runner",
    "summarize": "report", "write_report": "report", "load": "frame",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    # lazy: the sandbox child imports tooltransfer.planner.apps.batch.sandbox without numpy, pydantic, rich or scipy
    if name in _EXPORTS:
        return getattr(import_module(f"tooltransfer.planner.apps.batch.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module 'tooltransfer.planner.apps.batch' has no attribute {name!r}")
