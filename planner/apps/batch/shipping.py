"""The learned skills travel with the batch: learned once where the run starts, shipped to every
executor slot, and read there from a local skills file, so the workers need this package but not the
dataset, the same paths or the same working directory.

- :func:`batch_skills` learns them where ``batch run`` runs (the batch's dataset with the tasks'
  ``oe.k`` and ``ss.virtual_motion``, the SS skill and the identified push mechanics, through the
  skills cache) and returns a :class:`ShippedSkills`: the text of a skills file
  (``tooltransfer.skills/1``, :meth:`tooltransfer.planner.learning.skills.Skills.to_dict`, about 200 kB) and its digest.
- How they get to a slot (:meth:`tooltransfer.planner.apps.batch.executors.Slots.ship`): on the process pool the
  runner writes the file once into a temporary folder and each pool worker registers its path (the
  pool's initializer); on Dask a worker plugin (:class:`tooltransfer.planner.apps.batch.dask_plugin.SkillsPlugin`,
  registered once per run) writes it into every worker's local directory, also on workers that join
  the cluster later or restart.
- A job names the skills by digest (:attr:`tooltransfer.planner.apps.batch.worker.Job.skills`): its calls get this
  slot's local file as the task's ``skills: {file: ...}`` in place of the dataset (:func:`localize`).
  A slot that holds no skills of that digest turns the job into an ``error`` row naming the worker.

This module imports nothing heavy (the sandbox's parent, a Dask worker thread, imports it).
"""

from __future__ import annotations

import hashlib
import os
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

_LOCK = threading.Lock()
#: digest -> [local path, registrations, whether this process wrote the file (and removes it)]
_INSTALLED: dict[str, list[Any]] = {}


@dataclass(frozen=True)
class ShippedSkills:
    """The batch's skills as they travel.

    Attributes:
        digest: the first 16 hex digits of the text's SHA-256 (names the local file).
        text: a skills file (JSON, ``tooltransfer.skills/1``).
        dataset: the folder they were learned from, where the run started (for messages).
    """

    digest: str
    text: str
    dataset: str

    @classmethod
    def from_text(cls, text: str, dataset: str) -> ShippedSkills:
        return cls(_digest(text), text, dataset)

    @property
    def size(self) -> int:
        """Bytes of the skills file."""
        return len(self.text.encode())

    @property
    def file_name(self) -> str:
        return f"tooltransfer-skills-{self.digest}.json"


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def install(skills: ShippedSkills, folder: str | Path) -> str:
    """Write the skills file into ``folder`` (atomically, unless a file of the same content is there)
    and register it in this process under the digest; returns its path. Each call is matched by one
    :func:`release`."""
    from tooltransfer.atomic import write_text

    path = Path(folder) / skills.file_name
    with _LOCK:
        entry = _INSTALLED.get(skills.digest)
        if entry is not None and Path(entry[0]).is_file():
            entry[1] += 1
            return str(entry[0])
        same = path.is_file() and _digest(path.read_text(encoding="utf-8")) == skills.digest
        if not same:
            write_text(path, skills.text)
        _INSTALLED[skills.digest] = [str(path), 1, not same]
        return str(path)


def register(digest: str, path: str) -> None:
    """Register a skills file written elsewhere (the pool's: the runner wrote it) under ``digest``."""
    with _LOCK:
        entry = _INSTALLED.setdefault(digest, [str(path), 0, False])
        entry[1] += 1


def release(digest: str) -> None:
    """Undo one :func:`install` (or :func:`register`); the last one forgets the digest and removes a
    file this process wrote."""
    with _LOCK:
        entry = _INSTALLED.get(digest)
        if entry is None:
            return
        entry[1] -= 1
        if entry[1] > 0:
            return
        del _INSTALLED[digest]
    if entry[2]:
        try:
            os.unlink(entry[0])
        except OSError:
            pass


def local_path(digest: str) -> str | None:
    """This process's skills file of ``digest``, or None (never shipped here, or removed)."""
    with _LOCK:
        entry = _INSTALLED.get(digest)
    return entry[0] if entry is not None and os.path.isfile(entry[0]) else None


def localize(args: tuple, path: str) -> tuple:
    """``args`` of a call whose first argument is a task's fields, with the task's skills taken from
    the skills file at ``path`` (other calls' arguments are returned as they are)."""
    if args and isinstance(args[0], dict) and isinstance(args[0].get("skills"), dict):
        return ({**args[0], "skills": {"file": str(path)}}, *args[1:])
    return args


def batch_skills(spec: Any, batch_path: str | Path, first: Any) -> ShippedSkills | None:
    """The skills every job of the batch plans with, learned here (through the skills cache) from the
    batch's dataset with the first task's ``oe.k`` and ``ss.virtual_motion`` (every task has the same
    ones: they come from the batch file's ``task``), with the SS skill and the push mechanics.

    Returns None when the skills cannot be shipped but the batch can still run the old way, the
    dataset read by every worker at its path: a dataset whose demonstrations never switch faces (no
    SS skill; skills files hold one) while every variant uses the ``arch`` switches, which need none.

    Raises:
        DatasetError, InputError: the dataset or its skills (every job would fail on them).
    """
    import json

    from tooltransfer.errors import InputError
    from tooltransfer.planner.apps.batch.spec import dataset_folder
    from tooltransfer.planner.learning.skills import learn_skills
    from tooltransfer.planner.planning.variant_registry import needs_ss_skill
    from tooltransfer.problems.dataset import DatasetError
    from tooltransfer.problems.task import task_from_dict

    folder = dataset_folder(spec, batch_path)
    task = task_from_dict(first.data, str(Path(batch_path).resolve()))
    needs_ss = any(needs_ss_skill(ss) for _, ss in spec.variants.pairs())
    try:
        skills = learn_skills(folder, task.oe.k, task.ss.virtual_motion, with_ss=True)
    except DatasetError:
        raise
    except InputError as exc:
        if needs_ss or not exc.field.startswith("skills"):
            raise
        return None
    return ShippedSkills.from_text(json.dumps(skills.to_dict()), str(folder))
