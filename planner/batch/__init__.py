"""Batch feasibility studies: many generated tasks, every variant, in parallel, into SQLite.

- :mod:`planner.batch.spec`: batch files (``tooltransfer.batch/1``, pydantic);
- :mod:`planner.batch.generate`: deterministic random tasks, each a valid task file;
- :mod:`planner.batch.sandbox` and :mod:`planner.batch.worker`: each job isolated in a long-lived
  child process with a timeout (hangs, crashes and exceptions become rows);
- :mod:`planner.batch.executors`: a process pool or Dask distributed, one code path;
- :mod:`planner.batch.store`: the SQLite store (WAL, one row per task and variant, resumable);
- :mod:`planner.batch.runner`: submit, store as each finishes, progress, Ctrl-C;
- :mod:`planner.batch.report` and :mod:`planner.batch.figures`: tables, CSV, figures;
- :mod:`planner.batch.cli`: ``tooltransfer batch generate|run|report|schema``.

Scripts that call :func:`run_batch` must guard their entry point with ``if __name__ ==
"__main__":`` (the process pool spawns its workers, which import the main module).
"""

from planner.batch.generate import GeneratedTask, generate_tasks, write_tasks
from planner.batch.report import summarize, write_report
from planner.batch.runner import RunSummary, run_batch
from planner.batch.spec import BatchSpec, load_batch
from planner.batch.store import ResultStore

__all__ = [
    "BatchSpec",
    "GeneratedTask",
    "ResultStore",
    "RunSummary",
    "generate_tasks",
    "load_batch",
    "run_batch",
    "summarize",
    "write_report",
    "write_tasks",
]
