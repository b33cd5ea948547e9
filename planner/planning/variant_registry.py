"""The planner's variants in two tables: OE condensing (:data:`OE_VARIANTS`) and switch paths
(:data:`SS_VARIANTS`), each name mapped to what it needs.

Every consumer (``solve``, the closed loop, the batch runs, the figures, the benchmarks) asks these
tables instead of comparing variant names: a new variant is one entry here. An unknown name raises
:class:`UnknownVariantError`, which lists the registered ones. The task schema's ``Literal`` choices
(:mod:`tooltransfer.problems.variants`) name the same variants; ``tests/test_variant_registry.py``
checks that the two agree.

* OE: ``condense(t, universal, setting, target, options) -> PushPlan`` and its options type, made
  from the task's ``oe`` section by ``options_from_task``;
* SS: ``planner(setting, skill, ss) -> SwitchPlanner`` (``ss``: the task's ``ss`` section, ``skill``
  the SS skill or None), whether it needs an SS skill, and the variant it falls back to where it
  finds no path (:func:`switch_planner` applies that rule, the one place it is written).
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError, ToolTransferError
from tooltransfer.planner.planning.assemble import SwitchPlanner
from tooltransfer.planner.planning.oe.guided import guided_plans
from tooltransfer.planner.planning.oe.mapping_variant import MappingOptions, condense_mapping
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.qp_variant import condense_qp
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.planner.planning.ss import SwitchSkill, optimize, recombine
from tooltransfer.planner.planning.ss.grid_variant import grid_planner
from tooltransfer.planner.planning.switches import SkillSolver, arch_planner, dmp_planner, opt_planner, with_fallback
from tooltransfer.problems.task import OEOptions, SSOptions

#: ``condense(t (T,) [s], universal (T, 2) [m], setting, target (2,) [m] or None, options) -> PushPlan``.
Condense = Callable[[NDArray[np.float64], NDArray[np.float64], Setting, "NDArray[np.float64] | None", Any],
                    PushPlan]
#: ``guided(t, universal, setting, target, options) -> the push plans of a fallback search, one per attempt``;
#: the caller sends back why a solved one failed later (a switch with no tool path), or None.
Guided = Callable[[NDArray[np.float64], NDArray[np.float64], Setting, "NDArray[np.float64] | None", Any],
                  Generator[PushPlan, Any, None]]
#: ``planner(setting, skill or None, the task's ss options) -> SwitchPlanner``.
SwitchFactory = Callable[[Setting, "SwitchSkill | None", SSOptions], SwitchPlanner]


class UnknownVariantError(ToolTransferError, ValueError):
    """A variant name that is not registered; lists the registered ones.

    Attributes:
        kind: ``"oe"`` or ``"ss"``; name: the name asked for; registered: the names known.
    """

    def __init__(self, kind: str, name: str, registered: tuple[str, ...]) -> None:
        self.kind, self.name, self.registered = kind, name, registered
        super().__init__(f"unknown {kind} variant {name!r}; registered: {', '.join(registered)}")


@dataclass(frozen=True)
class OEVariant:
    """One OE condensing variant.

    Attributes:
        name: the name a task gives (``variants.oe``).
        condense: the condensing function (:data:`Condense`).
        options_type: the type of its options (a frozen pydantic model).
        options_from_task: its options from the task's ``oe`` section (validated by the schema).
        guided: a fallback search, tried when ``condense``'s plans fail: its push plans, one per attempt
            (the ``qp`` variant's guided search, :func:`~tooltransfer.planner.planning.oe.guided.guided_plans`),
            or None.
    """

    name: str
    condense: Condense
    options_type: type
    options_from_task: Callable[[OEOptions], Any]
    guided: Guided | None = None


@dataclass(frozen=True)
class SSVariant:
    """One switch-path variant.

    Attributes:
        name: the name a task gives (``variants.ss``).
        planner: its switch-planner factory (:data:`SwitchFactory`).
        needs_skill: whether it needs the SS skill (learned from the demonstrations).
        fallbacks: the variants whose paths are taken, in turn, where this one finds none.
        solve: how a skill variant solves one :class:`~tooltransfer.planner.planning.ss.SwitchTask` with its
            default options (``solve(skill, task) -> SwitchPath``, as the figures draw it); None for
            a variant without a skill.
    """

    name: str
    planner: SwitchFactory
    needs_skill: bool
    fallbacks: tuple[str, ...] = ()
    solve: SkillSolver | None = None


def _skill(name: str, skill: SwitchSkill | None) -> SwitchSkill:
    if skill is None:
        raise InputError("skills", "an SS skill for the switch variant " + repr(name), "none")
    return skill


#: The OE condensing variants by name.
OE_VARIANTS: Mapping[str, OEVariant] = MappingProxyType({
    "mapping": OEVariant("mapping", condense_mapping, MappingOptions, MappingOptions.from_task),
    "qp": OEVariant("qp", condense_qp, QPOptions, QPOptions.from_task, guided_plans),
})

#: The switch-path variants by name. ``opt``'s NLP is local: where it finds no path, the geometric
#: ``arch`` does, and where that finds none either, the ``grid`` search over all the tool's placements;
#: ``dmp`` reports what recombination gives, as the paper's method would.
SS_VARIANTS: Mapping[str, SSVariant] = MappingProxyType({
    "arch": SSVariant("arch", lambda setting, skill, ss: arch_planner(setting, ss.clearance), needs_skill=False),
    "dmp": SSVariant("dmp", lambda setting, skill, ss: dmp_planner(_skill("dmp", skill), setting), needs_skill=True,
                     solve=recombine),
    "grid": SSVariant("grid", lambda setting, skill, ss: grid_planner(setting, ss.clearance), needs_skill=False),
    "opt": SSVariant("opt", lambda setting, skill, ss: opt_planner(_skill("opt", skill), setting, ss.clearance,
                                                                   ss.n_knots), needs_skill=True,
                     fallbacks=("arch", "grid"),
                     solve=lambda skill, task: optimize(skill, task)),
})


def oe_variant(name: str) -> OEVariant:
    """The registered OE variant ``name``; raises :class:`UnknownVariantError`."""
    try:
        return OE_VARIANTS[name]
    except KeyError:
        raise UnknownVariantError("oe", name, tuple(OE_VARIANTS)) from None


def ss_variant(name: str) -> SSVariant:
    """The registered switch-path variant ``name``; raises :class:`UnknownVariantError`."""
    try:
        return SS_VARIANTS[name]
    except KeyError:
        raise UnknownVariantError("ss", name, tuple(SS_VARIANTS)) from None


def needs_ss_skill(name: str) -> bool:
    """Whether the switch variant ``name`` (or a variant it falls back to) needs the SS skill."""
    v = ss_variant(name)
    return v.needs_skill or any(needs_ss_skill(f) for f in v.fallbacks)


def switch_planner(name: str, setting: Setting, skill: SwitchSkill | None, ss: SSOptions) -> SwitchPlanner:
    """The switch planner of variant ``name`` in ``setting``, wrapped with its fallbacks in turn
    (:attr:`SSVariant.fallbacks`, :func:`tooltransfer.planner.planning.switches.with_fallback`).

    Raises:
        UnknownVariantError: ``name`` (or a fallback) is not registered.
        InputError: the variant needs an SS skill and ``skill`` is None.
    """
    v = ss_variant(name)
    planner = v.planner(setting, skill, ss)
    for fallback in v.fallbacks:
        planner = with_fallback(planner, switch_planner(fallback, setting, skill, ss), fallback)
    return planner


def oe_options(name: str, oe: OEOptions) -> Any:
    """The options of OE variant ``name`` from a task's ``oe`` section."""
    return oe_variant(name).options_from_task(oe)


def condense(name: str, t: NDArray[np.float64], universal: NDArray[np.float64], setting: Setting,
             target: NDArray[np.float64] | None = None, options: Any = None) -> PushPlan:
    """Condense ``universal`` (T, 2) [m] at times ``t`` (T,) [s] in ``setting`` with OE variant ``name``
    (``options`` of its :attr:`OEVariant.options_type`, default its defaults)."""
    return oe_variant(name).condense(t, universal, setting, target, options)


__all__ = ["OE_VARIANTS", "SS_VARIANTS", "Condense", "OEVariant", "SSVariant", "SwitchFactory",
           "UnknownVariantError", "condense", "needs_ss_skill", "oe_options", "oe_variant", "ss_variant",
           "switch_planner"]
