"""The learned skills a plan needs: the universal OE skill, the SS (switch) skill, and the push
mechanics identified from the recordings.

They come from a demonstration dataset (learned once, then cached by the dataset's content hash in
memory and as files in :func:`cache_dir` that carry a checksum of their content and of the dataset:
:mod:`tooltransfer.planner.learning.cache_file`; an edited one is learned again) or from a saved skills file written by
``tooltransfer learn`` (format ``tooltransfer.skills/1``)::

    {"format": "tooltransfer.skills/1",
     "dataset": "<folder it was learned from>", "dataset_sha256": "<content hash>",
     "oe": <a tooltransfer.oe/1 skill>, "ss": <a tooltransfer.ss/1 skill>,
     "mechanics": {"mu", "c", "source", "mu_std", "c_std"},      (optional)
     "identification": {<what the mechanics were identified from and how well they fit>}}  (optional)

The mechanics (``mu``, ``c`` of docs/design.md section 10) are identified by
:mod:`tooltransfer.planner.learning.identify` from the dataset's pushes, or from a calibration recording (``tooltransfer
demos --calibration``) when one is given; a file without them (written before they existed) loads with ``mechanics``
None.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tooltransfer.errors import InputError, SkillFileError
from tooltransfer.planner.learning.oe_skill import OESkill
from tooltransfer.planner.learning.switch_skill import SwitchSkill
from tooltransfer.problems.variants import MAPPING_K, VIRTUAL_MOTION
from tooltransfer.tools.pushing.mechanics import PushMechanics
from tooltransfer.versioned_json import check_format, format_tag, read_json, write_versioned

if TYPE_CHECKING:
    from tooltransfer.tools.pushing.identify import Identification

SKILLS_NAME, SKILLS_VERSION = "tooltransfer.skills", 1
"""Name and version of the skills file format (module docstring)."""
SKILLS_FORMAT = format_tag(SKILLS_NAME, SKILLS_VERSION)
MECHANICS_NAME, MECHANICS_VERSION = "tooltransfer.mechanics", 1
MECHANICS_FORMAT = format_tag(MECHANICS_NAME, MECHANICS_VERSION)
"""Format of the cached identification of a dataset (in :func:`cache_dir`)."""
SS_DEFAULT_CLEARANCE = 0.01
"""Offset [m] of the arch-shaped virtual object motion from the object's outline when learning."""

_MEMORY: dict[str, Any] = {}
_HASHES: dict[tuple[Any, ...], str] = {}


@dataclass(frozen=True)
class Skills:
    """Both skills and where they come from.

    Attributes:
        oe: the universal object-motion skill (learned with ``oe.k``).
        ss: the switch skill (the virtual object motion it was learned with: ``ss.virtual``); None
            when not asked for (the ``arch`` switches need none).
        dataset: the dataset folder they were learned from; dataset_sha256: its content hash.
        mechanics: the push mechanics identified from the recordings (``source="identified"``), or
            None (not identified, or an older skills file). A planner takes the task's override if
            given, else these, else :data:`tooltransfer.tools.pushing.mechanics.PLATFORM_MECHANICS`.
        identification: what the mechanics were identified from and how well they fit (the
            :meth:`tooltransfer.tools.pushing.identify.Identification.summary` and the recording's hash), or None.
    """

    oe: OESkill
    ss: SwitchSkill | None
    dataset: str
    dataset_sha256: str
    mechanics: PushMechanics | None = None
    identification: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain-data description, format ``tooltransfer.skills/1``."""
        if self.ss is None:
            raise InputError("skills.ss", "an SS skill to save (learn_skills(..., with_ss=True))", None)
        doc: dict[str, Any] = {"format": SKILLS_FORMAT, "dataset": self.dataset,
                               "dataset_sha256": self.dataset_sha256, "oe": self.oe.to_dict(),
                               "ss": self.ss.to_dict()}
        if self.mechanics is not None:
            doc["mechanics"] = self.mechanics.to_dict()
            if self.identification is not None:
                doc["identification"] = self.identification
        return doc

    def save(self, path: str | Path) -> Path:
        """Write the skills file (JSON; its parent folders are made), atomically (a temporary file
        beside it replaces it once complete: :func:`tooltransfer.versioned_json.write_versioned`); returns its path."""
        return write_versioned(path, self.to_dict(), mkdir=True)

    @classmethod
    def load(cls, path: str | Path) -> Skills:
        """Read a skills file; a missing or damaged file or another format raises
        :class:`~tooltransfer.errors.SkillFileError` naming the file."""
        src = str(path)
        doc = check_format(read_json(path), SKILLS_NAME, SKILLS_VERSION, src)
        for key in ("oe", "ss", "dataset", "dataset_sha256"):
            if key not in doc:
                raise SkillFileError(src, f"missing field {key!r}")
        mechanics, ident = None, None
        if doc.get("mechanics") is not None:
            try:
                mechanics = PushMechanics.from_dict(doc["mechanics"])
            except InputError as exc:
                raise SkillFileError(src, str(exc)) from None
            ident = doc.get("identification")
            if ident is not None and not isinstance(ident, dict):
                raise SkillFileError(src, f"identification: expected a mapping, got {type(ident).__name__}")
        return cls(OESkill.from_dict(doc["oe"], f"{src}:oe"), SwitchSkill.from_dict(doc["ss"], f"{src}:ss"),
                   str(doc["dataset"]), str(doc["dataset_sha256"]), mechanics, ident)


def dataset_files(folder: Path) -> list[Path]:
    """The files a dataset's skills are learned from: ``meta.yaml``, its demonstrations, ``truth.yaml``
    and a tool file (when ``tool`` is a path), those that exist, in that order."""
    from tooltransfer.problems.dataset import load_meta
    from tooltransfer.tools.library import library_names

    meta = load_meta(folder)  # a regular file of bounded size inside the folder
    names = ["meta.yaml", *meta.demonstrations, "truth.yaml"]
    if meta.tool not in library_names():
        names.append(meta.tool)
    return [folder / n for n in names if (folder / n).exists()]


def dataset_hash(folder: Path) -> str:
    """Content hash (SHA-256 hex) of a dataset: the name and bytes of each of its files
    (:func:`dataset_files`), each read as data (:func:`tooltransfer.regular_file.read_regular`: a
    regular file inside the folder, its size bounded before it is read), so a FIFO, a device, a link
    out of the folder or a sparse giant is refused by name at once. Kept in memory for the process while
    no file's name, size, modification time or inode changes (one planning run asks for it once per
    skill it reads)."""
    from tooltransfer.problems.dataset import MAX_CSV_BYTES, DatasetError
    from tooltransfer.regular_file import read_regular

    folder = Path(folder)
    files = dataset_files(folder)
    signature = tuple((p.name, (st := os.stat(p)).st_size, st.st_mtime_ns, st.st_ino) for p in files)
    key = (str(folder.resolve()), signature)
    if key not in _HASHES:
        h = hashlib.sha256()
        for p in files:
            h.update(str(p.relative_to(folder)).encode())
            h.update(read_regular(p, DatasetError, "dataset file", MAX_CSV_BYTES, inside=folder))
        _HASHES[key] = h.hexdigest()
    return _HASHES[key]


def cache_dir() -> Path:
    """Where learned skills are kept between runs: ``$TOOLTRANSFER_CACHE`` or ``~/.cache/tooltransfer``."""
    return Path(os.environ.get("TOOLTRANSFER_CACHE", Path.home() / ".cache" / "tooltransfer"))


def _check_dataset(folder: Path) -> Path:
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError("skills.dataset", "a dataset folder (meta.yaml and CSVs)", str(folder))
    return folder


def _cached(name: str, source: str, from_dict: Any, to_dict: Any, learn: Any) -> Any:
    """The object cached under ``name``, learned from the dataset of content hash ``source``: from
    memory, else the cache file if its checksum matches (:mod:`tooltransfer.planner.learning.cache_file`:
    a damaged, edited or foreign file is learned again and replaced), else learned and written (a
    read-only cache is skipped). ``from_dict(payload, source_name)`` and ``to_dict(obj)`` convert."""
    from tooltransfer.planner.learning.cache_file import read_cache, write_cache

    if name in _MEMORY:
        return _MEMORY[name]
    path = cache_dir() / name
    if path.is_file():
        payload = read_cache(path, source)
        if payload is not None:
            try:
                _MEMORY[name] = from_dict(payload, str(path))
                return _MEMORY[name]
            except SkillFileError:
                pass
    _MEMORY[name] = learn()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_cache(path, to_dict(_MEMORY[name]), source)
    except (OSError, ValueError):
        pass
    return _MEMORY[name]


def learn_oe_from_dataset(folder: Path, k: float) -> OESkill:
    """Learn the universal OE skill from a dataset (segmentation, recovery with ``k``, one DMP)."""
    from tooltransfer.planner.learning.oe_skill import learn_oe_skill
    from tooltransfer.planner.learning.segmentation import (
        segment,  # scipy.signal: half a second of imports, only to learn
    )
    from tooltransfer.problems.dataset import load_dataset

    ds = load_dataset(folder)
    tool = ds.tool()
    demos, fixed = [], []
    for d in ds.demonstrations:
        pushes = segment(d, tool, radius=float(ds.meta.object_radius)).demo_pushes(d)
        demos.append(pushes)
        fixed.append([i for i in range(len(pushes) - 1) if pushes[i].face != pushes[i + 1].face])
    return learn_oe_skill(demos, tool, k=k, fixed=fixed)


def learn_ss_from_dataset(folder: Path, virtual: str = VIRTUAL_MOTION) -> SwitchSkill:
    """Learn the SS skill from a dataset's switches (the most frequent pair of faces)."""
    from tooltransfer.planner.learning.switch_dataset import dataset_switches
    from tooltransfer.planner.learning.switch_skill import learn_switch_skill
    from tooltransfer.problems.dataset import load_dataset

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
    h = dataset_hash(folder)
    return _cached(f"oe-{h}-k{k}.json", h, OESkill.from_dict, OESkill.to_dict, lambda: learn_oe_from_dataset(folder, k))


def ss_skill_from_dataset(folder: Path, virtual: str = VIRTUAL_MOTION) -> SwitchSkill:
    """The SS skill of a dataset, cached by the dataset's content hash and the virtual motion."""
    folder = _check_dataset(folder)
    h = dataset_hash(folder)
    return _cached(f"ss-{h}-{virtual}.json", h, SwitchSkill.from_dict, SwitchSkill.to_dict,
                   lambda: learn_ss_from_dataset(folder, virtual))


def _identification_from_dict(doc: Any, source: str) -> Identification:
    from tooltransfer.tools.pushing.identify import Identification

    doc = check_format(doc, MECHANICS_NAME, MECHANICS_VERSION, source)
    try:
        return Identification.from_dict(doc.get("identification"), f"{source}:identification")
    except InputError as exc:
        raise SkillFileError(source, str(exc)) from None


IDENTIFICATION_VERSION = 2
"""Bumped when the identification's method changes, so cached results of an older one are not reused
(the cache is keyed by the dataset's content)."""


def _identification_to_dict(ident: Identification) -> dict[str, Any]:
    doc = {"format": MECHANICS_FORMAT, "identification": ident.to_dict()}
    json.dumps(doc, allow_nan=False)  # finite values only (a ValueError skips writing the cache)
    return doc


def identification_from_dataset(folder: str | Path) -> Identification:
    """The push mechanics identified from every push of a dataset (demonstrations or a calibration
    recording), cached by the dataset's content hash
    (:func:`tooltransfer.planner.learning.identify.identify_dataset`)."""
    folder = _check_dataset(Path(folder))
    h = dataset_hash(folder)
    return _cached(f"mech{IDENTIFICATION_VERSION}-{h}.json", h, _identification_from_dict, _identification_to_dict,
                   lambda: _identify(folder))


def _identify(folder: Path) -> Identification:
    from tooltransfer.planner.learning.identify import identify_dataset  # the dataset reader: only when not cached

    return identify_dataset(folder)


def learn_skills(folder: str | Path, k: float = MAPPING_K, virtual: str = VIRTUAL_MOTION, *, with_ss: bool = True,
                 calibration: str | Path | None = None, with_mechanics: bool = True) -> Skills:
    """The skills of a dataset (through the cache): the OE skill learned with ``k``, the SS skill with
    the ``virtual`` object motion (``"arch"`` or ``"line"``) unless ``with_ss`` is False, and the push
    mechanics identified from the ``calibration`` recording's pushes if one is given (a dataset
    folder), else from the dataset's own pushes (unless ``with_mechanics`` is False)."""
    folder = _check_dataset(Path(folder))
    ss = ss_skill_from_dataset(folder, virtual) if with_ss else None
    mechanics, summary = None, None
    if calibration is not None and not with_mechanics:
        raise InputError("calibration", "no calibration when with_mechanics is False", str(calibration))
    if with_mechanics:
        source = folder if calibration is None else Path(calibration)
        if calibration is not None and not source.is_dir():
            raise InputError("calibration", "a calibration dataset folder (tooltransfer demos --calibration)",
                             str(source))
        ident = identification_from_dataset(source)
        mechanics = ident.mechanics
        summary = {**ident.summary(), "dataset": str(source), "dataset_sha256": dataset_hash(source),
                   "kind": "demonstrations" if calibration is None else "calibration"}
    return Skills(oe_skill_from_dataset(folder, k), ss, str(folder), dataset_hash(folder), mechanics, summary)


def load_skills_file(path: str | Path) -> Skills:
    """A skills file, cached in memory by its path and modification time."""
    p = Path(path)
    if not p.is_file():
        raise InputError("skills.file", "an existing skills file (tooltransfer learn DATASET -o FILE)", str(p))
    key = f"file:{p.resolve()}:{p.stat().st_mtime_ns}"
    if key not in _MEMORY:
        _MEMORY[key] = Skills.load(p)
    return _MEMORY[key]
