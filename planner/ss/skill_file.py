"""Versioned SS skills file: the three DMPs of a :class:`~tooltransfer.planner.ss.learn.SwitchSkill` and the
choice of virtual object motion, as JSON.

Format ``tooltransfer.ss/1``::

    {"format": "tooltransfer.ss/1",
     "formulation": "<eq. (10) and (18) in words>",
     "virtual": "arch" | "line", "clearance" [m],
     "tool_shift" [m] (2,), "object_shift" [m] (2,), "winding" [rad],
     "tool", "faces" [from, to], "n_demos",
     "dmp_x", "dmp_o", "dmp_t": each a ``tooltransfer.dmp/1`` dictionary (:mod:`tooltransfer.dmp.skill_file`)}
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from tooltransfer.dmp.skill_file import dmp_from_dict, dmp_to_dict
from tooltransfer.errors import InputError, SkillFileError
from tooltransfer.planner.ss.learn import SwitchSkill
from tooltransfer.planner.ss.virtual import VIRTUAL_KINDS

FORMAT = "tooltransfer.ss"
VERSION = 1
FORMULATION = (
    "x - x_o = k1 (x^t - x_o) + k2 (x^o - x_o) (10), x = path of the first tool contact point, x_o = q_A; "
    "shared phase, gains and tau: f = k1 f^t + k2 f^o (18); learned with k1 = k2 = I: f^t = f - f^o; "
    "generalized with k1 = diag(new/demonstrated pure tool displacement), k2 = I (f^o fitted to the new x^o)"
)


def switch_skill_to_dict(skill: SwitchSkill) -> dict[str, Any]:
    """Plain-data description (JSON-serialisable)."""
    return {
        "format": f"{FORMAT}/{VERSION}",
        "formulation": FORMULATION,
        "virtual": skill.virtual,
        "clearance": skill.clearance,
        "tool_shift": skill.tool_shift.tolist(),
        "object_shift": skill.object_shift.tolist(),
        "winding": skill.winding,
        "tool": skill.tool,
        "faces": list(skill.faces),
        "n_demos": skill.n_demos,
        "dmp_x": dmp_to_dict(skill.dmp_x),
        "dmp_o": dmp_to_dict(skill.dmp_o),
        "dmp_t": dmp_to_dict(skill.dmp_t),
    }


def switch_skill_from_dict(data: dict[str, Any], source: str = "<dict>") -> SwitchSkill:
    """Rebuild a skill from :func:`switch_skill_to_dict` output; raises :class:`SkillFileError`."""
    if not isinstance(data, dict) or "format" not in data:
        raise SkillFileError(source, "not a tooltransfer skill file (no 'format' field)")
    name, _, ver = str(data["format"]).partition("/")
    if name != FORMAT:
        raise SkillFileError(source, f"format {data['format']!r} is not {FORMAT!r}")
    if ver != str(VERSION):
        raise SkillFileError(source, f"format version {ver!r} is not supported (this library reads {VERSION})")
    try:
        virtual = data["virtual"]
        if virtual not in VIRTUAL_KINDS:
            raise SkillFileError(source, f"'virtual' must be one of {VIRTUAL_KINDS}, got {virtual!r}")
        dmps = [dmp_from_dict(data[k], f"{source}:{k}") for k in ("dmp_x", "dmp_o", "dmp_t")]
        shifts = [np.asarray(data[k], dtype=np.float64).reshape(2) for k in ("tool_shift", "object_shift")]
        faces = tuple(str(f) for f in data["faces"])
        if len(faces) != 2:
            raise SkillFileError(source, "'faces' must name two faces")
        skill = SwitchSkill(
            dmp_x=dmps[0], dmp_o=dmps[1], dmp_t=dmps[2], virtual=virtual, clearance=float(data["clearance"]),
            tool_shift=shifts[0], object_shift=shifts[1], winding=float(data["winding"]), tool=str(data["tool"]),
            faces=(faces[0], faces[1]), n_demos=int(data["n_demos"]),
        )
    except KeyError as exc:
        raise SkillFileError(source, f"missing field {exc.args[0]!r}") from exc
    except (TypeError, ValueError, InputError) as exc:
        raise SkillFileError(source, f"invalid value: {exc}") from exc
    d = skill.dmp_x
    for other in (skill.dmp_o, skill.dmp_t):
        if (other.n_basis, other.alpha_z, other.beta_z, other.gamma) != (d.n_basis, d.alpha_z, d.beta_z, d.gamma):
            raise SkillFileError(source, "the three DMPs must share basis, gains and phase (eq. 18)")
    if not all(np.all(np.isfinite(v)) for v in (skill.tool_shift, skill.object_shift)):
        raise SkillFileError(source, "non-finite displacements")
    return skill


def save_switch_skill(skill: SwitchSkill, path: str | Path) -> None:
    """Write ``skill`` to ``path`` as JSON."""
    Path(path).write_text(json.dumps(switch_skill_to_dict(skill), indent=1))


def load_switch_skill(path: str | Path) -> SwitchSkill:
    """Read a skill written by :func:`save_switch_skill`."""
    from tooltransfer.dmp.skill_file import read_json

    return switch_skill_from_dict(read_json(path), str(path))
