"""Learning the SS skill from demonstrated switches (paper section III.B, steps 1-4; docs/design.md section 6).

Notation (docs/design.md section 6): ``x`` is the world path of the tool's first contact point ``p_A``
(the paper's point 2), ``x_o = q_A`` the first object contact point, ``x^o`` the virtual object
motion from ``q_A`` to ``q_B``, ``x^t`` the pure tool motion from ``x_o`` to ``x_o - R_B (p_B - p_A)``,
and (10) ``x - x_o = k1 (x^t - x_o) + k2 (x^o - x_o)`` with diagonal ``k1, k2``. Every path is
expressed relative to ``x_o`` (the skill is translation invariant).

Steps:

1. each demonstration gives ``x - x_o`` (from the tool track and its heading) and, for the chosen
   kind of virtual motion, ``x^o - x_o`` on the same times;
2. in the demonstrated case ``k1 = k2 = I`` (docs/design.md section 6; the printed (11) is not used);
3. alignment: every demonstration is mapped onto the one phase by its own duration (each keeps its
   ``tau``; :meth:`tooltransfer.dmp.primitive.DMP.fit`), and DMPs of ``x`` (f) and of ``x^o`` (f^o) are fitted
   on all demonstrations at once, with the same basis, gains and phase;
4. the pure tool skill from (18): ``f^t = k1^-1 (f - k2 f^o) = f - f^o``, i.e. ``W^t = W - W^o``.
   (Because the forcing targets and the ridge fit are linear in the path, this equals the DMP
   fitted on ``x - x^o + x_o`` directly; tests check it.)

A :class:`SwitchSkill` is saved as versioned JSON (:mod:`tooltransfer.versioned_json`), format ``tooltransfer.ss/1``::

    {"format": "tooltransfer.ss/1",
     "formulation": "<eq. (10) and (18) in words>",
     "virtual": "arch" | "line", "clearance" [m],
     "tool_shift" [m] (2,), "object_shift" [m] (2,), "winding" [rad],
     "tool", "faces" [from, to], "n_demos",
     "dmp_x", "dmp_o", "dmp_t": each a ``tooltransfer.dmp/1`` dictionary (:meth:`tooltransfer.dmp.DMP.to_dict`)}
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.primitive import DMP
from tooltransfer.errors import InputError, SkillFileError
from tooltransfer.planner.learning.demo_switch import DemoSwitch
from tooltransfer.planner.learning.virtual_motion import VIRTUAL_KINDS, VirtualKind, virtual_motion
from tooltransfer.tools.objects import Disc
from tooltransfer.versioned_json import check_format, format_tag, read_versioned, write_versioned

FORMAT = "tooltransfer.ss"
"""Name of the SS skill format (its files carry ``"format": "tooltransfer.ss/1"``)."""
VERSION = 1
"""Version of the SS skill format this library writes and reads."""
FORMULATION = (
    "x - x_o = k1 (x^t - x_o) + k2 (x^o - x_o) (10), x = path of the first tool contact point, x_o = q_A; "
    "shared phase, gains and tau: f = k1 f^t + k2 f^o (18); learned with k1 = k2 = I: f^t = f - f^o; "
    "generalized with k1 = diag(new/demonstrated pure tool displacement), k2 = I (f^o fitted to the new x^o)"
)
"""The equations a skill file's DMPs belong to, in words (stored in the file for a reader)."""


@dataclass
class SwitchSkill:
    """A learned SS skill.

    Attributes:
        dmp_x: DMP (2-D) of the demonstrated contact-point motion ``x - x_o`` (forcing term f).
        dmp_o: DMP of the demonstrated virtual object motion ``x^o - x_o`` (f^o).
        dmp_t: the pure tool skill ``x^t - x_o`` (f^t = f - f^o, eq. 18 with k1 = k2 = I).
        virtual: the kind of virtual object motion, ``"arch"`` or ``"line"``.
        clearance: the arch's offset from the outline [m] (unused by ``"line"``).
        tool_shift: shape (2,), mean demonstrated pure tool displacement ``-R_B (p_B - p_A)`` [m].
        object_shift: shape (2,), mean demonstrated virtual object displacement ``q_B - q_A`` [m].
        winding: mean signed angle [rad] the demonstrations turn about the object (+: CCW).
        tool: name of the demonstration tool; faces: ``(face_from, face_to)`` of the demonstrations.
        n_demos: number of demonstrations learned from.
    """

    dmp_x: DMP
    dmp_o: DMP
    dmp_t: DMP
    virtual: VirtualKind
    clearance: float
    tool_shift: NDArray[np.float64]
    object_shift: NDArray[np.float64]
    winding: float
    tool: str = ""
    faces: tuple[str, str] = ("", "")
    n_demos: int = 0

    @property
    def tau(self) -> float:
        """Mean demonstrated duration [s] (the skill's default switch duration)."""
        return self.dmp_x.tau

    def new_dmp(self) -> DMP:
        """An unfitted DMP with this skill's basis, gains and phase (for f^o of a new case)."""
        d = self.dmp_x
        return DMP(2, n_basis=d.n_basis, alpha_z=d.alpha_z, beta_z=d.beta_z, gamma=d.gamma, scaling=d.scaling,
                   ridge=d.ridge)

    def to_dict(self) -> dict[str, Any]:
        """Plain-data description, format ``tooltransfer.ss/1`` (JSON-serialisable; module docstring)."""
        return {
            "format": format_tag(FORMAT, VERSION),
            "formulation": FORMULATION,
            "virtual": self.virtual,
            "clearance": self.clearance,
            "tool_shift": self.tool_shift.tolist(),
            "object_shift": self.object_shift.tolist(),
            "winding": self.winding,
            "tool": self.tool,
            "faces": list(self.faces),
            "n_demos": self.n_demos,
            "dmp_x": self.dmp_x.to_dict(),
            "dmp_o": self.dmp_o.to_dict(),
            "dmp_t": self.dmp_t.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> SwitchSkill:
        """Rebuild a skill from :meth:`to_dict` output; another format or version, a missing field or
        damaged values raise :class:`~tooltransfer.errors.SkillFileError` naming ``source``."""
        check_format(data, FORMAT, VERSION, source)
        try:
            virtual = data["virtual"]
            if virtual not in VIRTUAL_KINDS:
                raise SkillFileError(source, f"'virtual' must be one of {VIRTUAL_KINDS}, got {virtual!r}")
            dmps = [DMP.from_dict(data[k], f"{source}:{k}") for k in ("dmp_x", "dmp_o", "dmp_t")]
            shifts = [np.asarray(data[k], dtype=np.float64).reshape(2) for k in ("tool_shift", "object_shift")]
            faces = tuple(str(f) for f in data["faces"])
            if len(faces) != 2:
                raise SkillFileError(source, "'faces' must name two faces")
            skill = cls(
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

    def save(self, path: str | Path) -> None:
        """Save as a versioned skills file (:meth:`to_dict`), atomically
        (:func:`tooltransfer.versioned_json.write_versioned`)."""
        write_versioned(path, self.to_dict(), indent=1)

    @classmethod
    def load(cls, path: str | Path) -> SwitchSkill:
        """Load a skill saved by :meth:`save`; a missing or damaged file or another format raises
        :class:`~tooltransfer.errors.SkillFileError`."""
        return cls.from_dict(read_versioned(path, FORMAT, VERSION), str(path))


@dataclass(frozen=True)
class AlignedDemo:
    """One demonstration decomposed for learning: times from 0 (T,) [s]; ``x``, ``x_o``, ``x_t``
    (T, 2) [m] relative to its ``x_o = q_A`` (2,)."""

    t: NDArray[np.float64]
    x: NDArray[np.float64]
    x_virtual: NDArray[np.float64]
    x_tool: NDArray[np.float64]
    origin: NDArray[np.float64]


def decompose(demo: DemoSwitch, virtual: VirtualKind, clearance: float) -> AlignedDemo:
    """Step 1 for one demonstration: ``x``, ``x^o`` (same times, the demonstration's way round the
    object) and ``x^t = x - x^o + x_o`` (k1 = k2 = I), all relative to ``x_o = q_A``."""
    t = demo.t - demo.t[0]
    xo = demo.object_point_from
    x = demo.contact_point_path() - xo
    xv = virtual_motion(virtual, t, demo.object_point_from, demo.object_point_to, Disc(demo.centre, demo.radius),
                        clearance=clearance, way=demo.winding()) - xo
    return AlignedDemo(t, x, xv, x - xv, xo.copy())


def learn_switch_skill(
    demos: Sequence[DemoSwitch],
    *,
    virtual: VirtualKind = "arch",
    clearance: float = 0.01,
    n_basis: int = 30,
    alpha_z: float = 25.0,
    ridge: float = 1e-8,
    tool: str = "",
) -> SwitchSkill:
    """Learn the SS skill from demonstrated switches (module docstring, steps 1-4).

    Args:
        demos: the demonstrated switches (at least one), all of the same pair of faces.
        virtual: the kind of virtual object motion (:mod:`tooltransfer.planner.learning.virtual_motion`).
        clearance: the arch's offset from the outline [m].
        n_basis, alpha_z, ridge: DMP settings (:class:`tooltransfer.dmp.primitive.DMP`; scaling ``"none"`` as the
        paper).
        tool: name of the demonstration tool (recorded in the skill).
    """
    demos = list(demos)
    if not demos or not all(isinstance(d, DemoSwitch) for d in demos):
        raise InputError("demos", "a non-empty sequence of DemoSwitch")
    if virtual not in VIRTUAL_KINDS:
        raise InputError("virtual", f"one of {', '.join(VIRTUAL_KINDS)}", repr(virtual))
    if not np.isfinite(clearance) or clearance < 0:
        raise InputError("clearance", "a finite length >= 0 [m]", repr(clearance))
    pairs = {(d.face_from, d.face_to) for d in demos}
    if len(pairs) != 1:
        raise InputError("demos", "switches between one pair of faces", sorted(pairs))
    parts = [decompose(d, virtual, clearance) for d in demos]
    ts = [p.t for p in parts]
    dmp_x = DMP(2, n_basis=n_basis, alpha_z=alpha_z, ridge=ridge).fit(ts, [p.x for p in parts])
    dmp_o = DMP(2, n_basis=n_basis, alpha_z=alpha_z, ridge=ridge).fit(ts, [p.x_virtual for p in parts])
    dmp_t = DMP(2, n_basis=n_basis, alpha_z=alpha_z, ridge=ridge)
    dmp_t.weights = dmp_x.weights - dmp_o.weights  # eq. (18) with k1 = k2 = I
    dmp_t.tau = dmp_x.tau
    dmp_t.x0 = dmp_x.x0 - dmp_o.x0
    dmp_t.g = dmp_x.g - dmp_o.g
    dmp_t.fit_method = "forcing (eq. 18: f^t = f - f^o)"
    face_pair = next(iter(pairs))
    return SwitchSkill(
        dmp_x=dmp_x,
        dmp_o=dmp_o,
        dmp_t=dmp_t,
        virtual=virtual,
        clearance=float(clearance),
        tool_shift=np.mean([d.tool_shift() for d in demos], axis=0),
        object_shift=np.mean([d.object_shift() for d in demos], axis=0),
        winding=float(np.mean([d.winding() for d in demos])),
        tool=tool,
        faces=face_pair,
        n_demos=len(demos),
    )
