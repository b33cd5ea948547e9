"""The task schema's choices and the defaults other layers name, in a module without heavy imports
(the CLI builds its parser from it without loading pydantic or numpy).

:mod:`tooltransfer.problems.task` uses these in its fields: they are the one place each is written.
"""

from __future__ import annotations

from typing import Any, Literal, get_args

#: The OE condensing variants a task may name (``variants.oe``, ``tooltransfer solve --oe``).
OEVariant = Literal["mapping", "qp"]
#: The switch variants a task may name (``variants.ss``, ``tooltransfer solve --ss``).
SSVariant = Literal["arch", "dmp", "grid", "opt"]
#: The SS skill's virtual object motions (``ss.virtual_motion``, ``tooltransfer learn --virtual``).
VirtualMotion = Literal["arch", "line"]
#: Default virtual object motion of the SS skill (``ss.virtual_motion``).
VIRTUAL_MOTION: VirtualMotion = "arch"

#: Default safety margin [m] (``safety_margin``, the paper's delta of section IV.E).
SAFETY_MARGIN = 0.005
#: Default adjusting factor of the mappings (6)-(7) (``oe.k``), in (0, 1).
MAPPING_K = 0.5


def choices(literal: Any) -> tuple[str, ...]:
    """The values of one of the ``Literal`` types above, for a CLI's choices."""
    return tuple(get_args(literal))


__all__ = ["MAPPING_K", "SAFETY_MARGIN", "VIRTUAL_MOTION", "OEVariant", "SSVariant", "VirtualMotion", "choices"]
