"""Tools whose faces are derived from their outline, and the map from hand-named faces to derived ones.

A tool file (or a task's inline tool) with an ``outline`` and no ``faces`` gets the faces of
:func:`~tooltransfer.tools.derive.faces.derive_faces` for the object and friction it is loaded for
(:func:`derived_tool`); :func:`with_derived_faces` replaces a hand-annotated tool's faces by derived
ones when asked. :func:`match_faces` names, for each hand-written face, the derived face on the same
edge whose normal agrees within :data:`MATCH_ANGLE`.
"""

from __future__ import annotations

import numpy as np
import shapely

from tooltransfer.tools.derive.faces import (
    DEFAULT_C,
    DEFAULT_FRICTION,
    MAX_DERIVED_FACES,
    MIN_LENGTH,
    Derivation,
    derive_faces,
)
from tooltransfer.tools.errors import ToolSpecError
from tooltransfer.tools.model import Face, Tool
from tooltransfer.tools.objects import OBJECT_RADIUS
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.pose import wrap_angle

#: Largest angle [rad] between a hand-written face's normal and its derived face's (1 degree).
MATCH_ANGLE = float(np.radians(1.0))
#: Distance [m] within which a hand-written face's end points lie on the derived face's edge.
MATCH_DISTANCE = 1e-7


def derived_tool(
    name: str,
    outline: shapely.Polygon,
    a_t: float,
    *,
    description: str = "",
    notes: str = "",
    object_radius: float | None = None,
    friction: float | None = None,
    c: float = DEFAULT_C,
    platform: OmniPlatform | None = None,
    min_length: float = MIN_LENGTH,
    max_faces: int = MAX_DERIVED_FACES,
) -> Tool:
    """A :class:`Tool` with the faces derived from ``outline`` for a disc of ``object_radius`` [m]
    (default the paper's 17.5 mm) and tool-object friction ``friction`` (default 0.8), on
    ``platform`` (default the Omni with ``a_t``).

    Raises:
        ToolSpecError: naming the tool and ``outline`` when no face can be derived.
    """
    from tooltransfer.errors import InputError

    try:  # checks the name, a_t and the outline first; a tool without faces is then refused
        Tool(name, outline, (), a_t, description, notes)
    except ToolSpecError as exc:
        if exc.field != "faces":
            raise
    try:
        derivation = derive_faces(
            shapely.geometry.polygon.orient(outline, sign=1.0),
            OBJECT_RADIUS if object_radius is None else object_radius,
            DEFAULT_FRICTION if friction is None else friction,
            c=c, min_length=min_length, max_faces=max_faces,
            platform=platform if platform is not None else OmniPlatform(a_t=a_t),
        )
    except InputError as exc:
        raise ToolSpecError(name, "outline", f"faces cannot be derived: {exc}") from None
    return Tool(name, outline, derivation.faces, a_t, description, notes)


def with_derived_faces(tool: Tool, **options: object) -> Tool:
    """``tool`` with its faces replaced by the ones derived from its outline (``options`` as for
    :func:`derived_tool`)."""
    return derived_tool(tool.name, tool.outline, tool.a_t, description=tool.description, notes=tool.notes,
                        **options)  # type: ignore[arg-type]


def match_faces(faces: tuple[Face, ...], derivation: Derivation | tuple[Face, ...]) -> dict[str, str | None]:
    """For each face of ``faces`` (hand-written), the name of the derived face on the same edge (both
    end points within :data:`MATCH_DISTANCE` of it) whose outward normal is within
    :data:`MATCH_ANGLE`, or None."""
    derived = derivation.faces if isinstance(derivation, Derivation) else derivation
    out: dict[str, str | None] = {}
    for f in faces:
        out[f.name] = None
        for d in derived:
            e = d.end - d.start
            length = float(np.hypot(*e))
            ends_on = all(abs(float(e[0] * (p - d.start)[1] - e[1] * (p - d.start)[0])) / length <= MATCH_DISTANCE
                          and -MATCH_DISTANCE <= float((p - d.start) @ e) / length <= length + MATCH_DISTANCE
                          for p in (f.start, f.end))
            if ends_on and abs(wrap_angle(d.normal_angle - f.normal_angle)) <= MATCH_ANGLE:
                out[f.name] = d.name
                break
    return out
