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
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.primitive import DMP
from tooltransfer.errors import InputError
from tooltransfer.planner.ss.demonstrated import DemoSwitch
from tooltransfer.planner.ss.virtual import VIRTUAL_KINDS, VirtualKind, virtual_motion
from tooltransfer.tools.objects import Disc


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

    def save(self, path: str) -> None:
        """Save as a versioned skills file (:mod:`tooltransfer.planner.ss.skill_file`)."""
        from tooltransfer.planner.ss.skill_file import save_switch_skill

        save_switch_skill(self, path)

    @classmethod
    def load(cls, path: str) -> SwitchSkill:
        """Load a skill saved by :meth:`save`; raises :class:`~tooltransfer.errors.SkillFileError`."""
        from tooltransfer.planner.ss.skill_file import load_switch_skill

        return load_switch_skill(path)


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
        virtual: the kind of virtual object motion (:mod:`tooltransfer.planner.ss.virtual`).
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
