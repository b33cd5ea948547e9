"""The Dask worker plugin that puts the batch's skills on every worker (:mod:`tooltransfer.planner.batch.shipping`).

Registered once per run (:meth:`tooltransfer.planner.batch.executors.Slots.ship`); the scheduler keeps it and
installs it on every worker, those that join the cluster later (dask-jobqueue's ``adapt``, a
Kubernetes worker group scaled up) and those that restart. ``setup`` writes the skills file into the
worker's local directory (``dask worker --local-directory``; the temporary folder if it cannot be
written); ``teardown`` (the run unregisters the
plugin when it ends, or the worker closes) removes it once no other run on the worker holds the
same skills.
"""

from __future__ import annotations

import tempfile
from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

from tooltransfer.planner.batch.shipping import ShippedSkills, install, release


class SkillsPlugin(WorkerPlugin):
    """Installs ``skills`` on each worker it is set up on."""

    def __init__(self, skills: ShippedSkills) -> None:
        self.skills = skills

    def setup(self, worker: Any) -> None:
        try:
            install(self.skills, worker.local_directory)
        except OSError:  # a local directory it cannot write: the machine's temporary folder
            install(self.skills, tempfile.gettempdir())

    def teardown(self, worker: Any) -> None:
        release(self.skills.digest)
