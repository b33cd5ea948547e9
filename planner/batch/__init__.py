"""Batch feasibility studies: many generated tasks, every variant, in parallel, into SQLite.

- :mod:`tooltransfer.planner.batch.spec`: batch files (``tooltransfer.batch/1``, pydantic);
- :mod:`tooltransfer.planner.batch.generate`: deterministic random tasks, each a valid task file;
- :mod:`tooltransfer.planner.batch.sandbox` and :mod:`tooltransfer.planner.batch.worker`: each job isolated in a
long-lived
  child process with a timeout (hangs, crashes and exceptions become rows);
- :mod:`tooltransfer.planner.batch.executors`: a process pool or Dask distributed, one code path;
- :mod:`tooltransfer.planner.batch.store`: the SQLite store (WAL, one row per task and variant, resumable);
- :mod:`tooltransfer.planner.batch.runner`: submit, store as each finishes, progress, Ctrl-C;
- :mod:`tooltransfer.planner.batch.report` and :mod:`tooltransfer.planner.plots.batch_figures`: tables, CSV, figures;
- :mod:`tooltransfer.planner.batch.cli`: ``tooltransfer batch generate|run|report|schema``.

Scripts that call :func:`run_batch` must guard their entry point with ``if __name__ ==
"__main__":`` (the process pool spawns its workers, which import the main module).
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

_EXPORTS = {
    "BatchSpec": "spec", "load_batch": "spec", "GeneratedTask": "generate", "generate_tasks": "generate",
    "write_tasks": "generate", "ResultStore": "store", "RunSummary": "runner", "run_batch": "runner",
    "summarize": "report", "write_report": "report",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    # lazy: the sandbox child imports tooltransfer.planner.batch.sandbox without numpy, pydantic, rich or scipy
    if name in _EXPORTS:
        return getattr(import_module(f"tooltransfer.planner.batch.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module 'tooltransfer.planner.batch' has no attribute {name!r}")
