"""Tying a results store to its batch and the settings it runs with, before any job runs.

A store holds one batch (its digest), is filled only on ``--resume`` and keeps the execution setting it was
started with (``simulate``); :func:`open_batch_store` refuses the others with the option to change.
"""

from __future__ import annotations

from collections.abc import Sequence

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.batch.generate import GeneratedTask
from tooltransfer.planner.apps.batch.jobs import simulate_setting, task_records
from tooltransfer.planner.apps.batch.spec import BatchSpec
from tooltransfer.planner.apps.batch.store import ResultStore

__all__ = ["open_batch_store"]


def _on_off(v: bool) -> str:
    return "on" if v else "off"


def open_batch_store(store: ResultStore, spec: BatchSpec, tasks: Sequence[GeneratedTask], resume: bool,
                     simulate: bool | None = None) -> None:
    """Tie ``store`` to the batch and its settings, refusing: a file of an older schema, another
    batch's store, a filled one without ``resume``, one holding values of the wrong kind
    (:meth:`~tooltransfer.planner.apps.batch.store.ResultStore.check_rows`), and one filled with the
    other execution setting (``simulate``, default the batch file's: see
    :func:`tooltransfer.planner.apps.batch.jobs.simulate_setting`)."""
    from tooltransfer.planner.apps.batch.store import SCHEMA_VERSION

    if store.schema != SCHEMA_VERSION:
        raise InputError("--db", f"a results file of schema {SCHEMA_VERSION} to resume, or a new file",
                         f"{store.path} of schema {store.schema} (written before executions were stored; "
                         "`tooltransfer batch report` still reads it)")
    meta = store.meta()
    digest = spec.digest()
    if meta.get("batch_digest") not in (None, digest):
        raise InputError("--db", f"a results file of this batch ({spec.name}, {digest}) or a new file",
                         f"{store.path} holds batch {meta.get('batch_name')} ({meta.get('batch_digest')})")
    n = store.count()
    if n and not resume:
        raise InputError("--resume", f"--resume to carry on ({store.path} already holds {n} results) "
                         "or a new --db", "neither")
    if n:
        store.check_rows()  # numbers where numbers belong, before anything is added to them
    sim = _on_off(simulate_setting(spec, simulate))
    was = meta.get("simulate")
    if n and was not in (None, sim):
        how = {"on": "--simulate, or simulate.enabled: true in the batch file",
               "off": "--no-simulate, or simulate.enabled: false in the batch file without --simulate"}
        raise InputError("--simulate", f"the setting {store.path} was run with, simulate {was} ({how[was]})",
                         f"simulate {sim}: resume with the same setting, or run into a new --db")
    store.set_meta(batch_name=spec.name, batch_digest=digest, batch=spec.model_dump_json(), simulate=sim)
    store.add_tasks(task_records(tasks))
