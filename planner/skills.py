"""The learned skills a plan needs: the universal OE skill and the SS (switch) skill.

They come from a demonstration dataset (learned once, then cached by the dataset's content hash in
memory and as skill files in :func:`cache_dir`) or from a saved skills file written by
``tooltransfer learn`` (format ``tooltransfer.skills/1``)::

    {"format": "tooltransfer.skills/1",
     "dataset": "<folder it was learned from>", "dataset_sha256": "<content hash>",
     "oe": <a tooltransfer.oe/1 skill>, "ss": <a tooltransfer.ss/1 skill>}
"""

from __future__ import annotations

import hashlib
import json
import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dmp.errors import InputError, SkillFileError
from dmp.skill_file import read_json
from planner.oe.learn import OESkill
from planner.ss.learn import SwitchSkill

SKILLS_FORMAT = "tooltransfer.skills/1"
SS_DEFAULT_CLEARANCE = 0.01
"""Offset [m] of the arch-shaped virtual object motion from the object's outline when learning."""

_MEMORY: dict[str, Any] = {}


@dataclass(frozen=True)
class Skills:
    """Both skills and where they come from.

    Attributes:
        oe: the universal object-motion skill (learned with ``oe.k``).
        ss: the switch skill (the virtual object motion it was learned with: ``ss.virtual``); None
            when not asked for (the ``arch`` switches need none).
        dataset: the dataset folder they were learned from; dataset_sha256: its content hash.
    """

    oe: OESkill
    ss: SwitchSkill | None
    dataset: str
    dataset_sha256: str

    def to_dict(self) -> dict[str, Any]:
        """Plain-data description, format ``tooltransfer.skills/1``."""
        from planner.ss.skill_file import switch_skill_to_dict

        if self.ss is None:
            raise InputError("skills.ss", "an SS skill to save (learn_skills(..., with_ss=True))", None)
        return {"format": SKILLS_FORMAT, "dataset": self.dataset, "dataset_sha256": self.dataset_sha256,
                "oe": self.oe.to_dict(), "ss": switch_skill_to_dict(self.ss)}

    def save(self, path: str | Path) -> Path:
        """Write the skills file (JSON); returns its path."""
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(json.dumps(self.to_dict()))
        return p

    @classmethod
    def load(cls, path: str | Path) -> Skills:
        """Read a skills file; a missing or damaged file or another format raises
        :class:`~dmp.errors.SkillFileError` naming the file."""
        from planner.ss.skill_file import switch_skill_from_dict

        doc = read_json(path)
        src = str(path)
        if not isinstance(doc, dict) or doc.get("format") != SKILLS_FORMAT:
            got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
            raise SkillFileError(src, f"expected format {SKILLS_FORMAT!r}, got {got!r}")
        for key in ("oe", "ss", "dataset", "dataset_sha256"):
            if key not in doc:
                raise SkillFileError(src, f"missing field {key!r}")
        return cls(OESkill.from_dict(doc["oe"], f"{src}:oe"), switch_skill_from_dict(doc["ss"], f"{src}:ss"),
                   str(doc["dataset"]), str(doc["dataset_sha256"]))


def dataset_hash(folder: Path) -> str:
    """Content hash (SHA-256 hex) of a dataset folder: every file's name and bytes."""
    h = hashlib.sha256()
    for p in sorted(folder.iterdir()):
        if p.is_file():
            h.update(p.name.encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def cache_dir() -> Path:
    """Where learned skills are kept between runs: ``$TOOLTRANSFER_CACHE`` or ``~/.cache/tooltransfer``."""
    return Path(os.environ.get("TOOLTRANSFER_CACHE", Path.home() / ".cache" / "tooltransfer"))


def _check_dataset(folder: Path) -> Path:
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError("skills.dataset", "a dataset folder (meta.yaml and CSVs)", str(folder))
    return folder


def _cached(name: str, load: Any, save: Any, learn: Any) -> Any:
    """The object cached under ``name``: from memory, else the cache file (a damaged file is
    relearned), else learned and written (a read-only cache is skipped)."""
    if name in _MEMORY:
        return _MEMORY[name]
    path = cache_dir() / name
    if path.is_file():
        try:
            _MEMORY[name] = load(path)
            return _MEMORY[name]
        except SkillFileError:
            path.unlink(missing_ok=True)
    _MEMORY[name] = learn()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        save(_MEMORY[name], path)
    except OSError:
        pass
    return _MEMORY[name]


def learn_oe_from_dataset(folder: Path, k: float) -> OESkill:
    """Learn the universal OE skill from a dataset (segmentation, recovery with ``k``, one DMP)."""
    from planner.oe.learn import learn_oe_skill
    from planner.segmentation import segment  # scipy.signal: half a second of imports, only to learn
    from problems.dataset import load_dataset

    ds = load_dataset(folder)
    tool = ds.tool()
    demos, fixed = [], []
    for d in ds.demonstrations:
        pushes = segment(d, tool, radius=float(ds.meta.object_radius)).demo_pushes(d)
        demos.append(pushes)
        fixed.append([i for i in range(len(pushes) - 1) if pushes[i].face != pushes[i + 1].face])
    return learn_oe_skill(demos, tool, k=k, fixed=fixed)


def learn_ss_from_dataset(folder: Path, virtual: str = "arch") -> SwitchSkill:
    """Learn the SS skill from a dataset's switches (the most frequent pair of faces)."""
    from planner.ss import learn_switch_skill
    from planner.ss.adapter import dataset_switches
    from problems.dataset import load_dataset

    switches = dataset_switches(folder, faces=None)
    if not switches:
        raise InputError("skills.dataset", "a dataset whose demonstrations switch faces at least once", str(folder))
    pair, _ = Counter((s.face_from, s.face_to) for s in switches).most_common(1)[0]
    chosen = [s for s in switches if (s.face_from, s.face_to) == pair]
    return learn_switch_skill(chosen, virtual=virtual, clearance=SS_DEFAULT_CLEARANCE,  # type: ignore[arg-type]
                              tool=load_dataset(folder).meta.tool)


def oe_skill_from_dataset(folder: Path, k: float) -> OESkill:
    """The OE skill of a dataset, cached by the dataset's content hash and ``k``."""
    folder = _check_dataset(folder)
    return _cached(f"oe-{dataset_hash(folder)}-k{k}.json", OESkill.load, lambda s, p: s.save(p),
                   lambda: learn_oe_from_dataset(folder, k))


def ss_skill_from_dataset(folder: Path, virtual: str = "arch") -> SwitchSkill:
    """The SS skill of a dataset, cached by the dataset's content hash and the virtual motion."""
    from planner.ss import load_switch_skill, save_switch_skill

    folder = _check_dataset(folder)
    return _cached(f"ss-{dataset_hash(folder)}-{virtual}.json", load_switch_skill, save_switch_skill,
                   lambda: learn_ss_from_dataset(folder, virtual))


def learn_skills(folder: str | Path, k: float = 0.5, virtual: str = "arch", *, with_ss: bool = True) -> Skills:
    """The skills of a dataset (through the cache): the OE skill learned with ``k``, the SS skill with
    the ``virtual`` object motion (``"arch"`` or ``"line"``) unless ``with_ss`` is False."""
    folder = _check_dataset(Path(folder))
    ss = ss_skill_from_dataset(folder, virtual) if with_ss else None
    return Skills(oe_skill_from_dataset(folder, k), ss, str(folder), dataset_hash(folder))


def load_skills_file(path: str | Path) -> Skills:
    """A skills file, cached in memory by its path and modification time."""
    p = Path(path)
    if not p.is_file():
        raise InputError("skills.file", "an existing skills file (tooltransfer learn DATASET -o FILE)", str(p))
    key = f"file:{p.resolve()}:{p.stat().st_mtime_ns}"
    if key not in _MEMORY:
        _MEMORY[key] = Skills.load(p)
    return _MEMORY[key]
