"""Contact faces derived from a tool's outline (docs/design.md section 13).

* :func:`derive_faces` (:mod:`.faces`): every usable edge and vertex contact of an outline for a disc of
  a given radius and friction, and the planner faces (``edge_<i>``) they give.
* :func:`outline_from` (:mod:`.outline`): an outline from points, SVG path data, an SVG file or a tool file.
* :func:`derived_tool`, :func:`with_derived_faces`, :func:`match_faces` (:mod:`.tool`): tools with
  derived faces, and which derived face each hand-written face is.
* :func:`plot_derivation` (:mod:`.plot`, matplotlib): the outline with its contacts, normals and cones.

The names are imported on first use: :mod:`.defaults` (the default settings, no numpy or shapely) can
be imported without the rest.
"""

from typing import TYPE_CHECKING, Any

from tooltransfer.lazy import lazy_attribute

if TYPE_CHECKING:
    from tooltransfer.tools.derive.contacts import EdgeContact, VertexContact
    from tooltransfer.tools.derive.defaults import (
        ARC_TOLERANCE,
        CONTACT_WINDOW,
        DEFAULT_C,
        DEFAULT_FRICTION,
        MAX_DERIVED_FACES,
        MIN_LENGTH,
        SVG_SCALE,
    )
    from tooltransfer.tools.derive.faces import Derivation, derive_faces
    from tooltransfer.tools.derive.outline import outline_from, svg_polygon
    from tooltransfer.tools.derive.tool import MATCH_ANGLE, derived_tool, match_faces, with_derived_faces

#: Each public name and its submodule.
_HOMES = {
    "EdgeContact": "contacts", "VertexContact": "contacts", "ARC_TOLERANCE": "defaults", "CONTACT_WINDOW": "defaults",
    "DEFAULT_C": "defaults", "DEFAULT_FRICTION": "defaults", "MAX_DERIVED_FACES": "defaults", "MIN_LENGTH": "defaults",
    "SVG_SCALE": "defaults", "Derivation": "faces", "derive_faces": "faces", "outline_from": "outline",
    "svg_polygon": "outline", "MATCH_ANGLE": "tool", "derived_tool": "tool", "match_faces": "tool",
    "with_derived_faces": "tool",
}

__all__ = [
    "ARC_TOLERANCE",
    "CONTACT_WINDOW",
    "DEFAULT_C",
    "DEFAULT_FRICTION",
    "MATCH_ANGLE",
    "MAX_DERIVED_FACES",
    "MIN_LENGTH",
    "SVG_SCALE",
    "Derivation",
    "EdgeContact",
    "VertexContact",
    "derive_faces",
    "derived_tool",
    "match_faces",
    "outline_from",
    "svg_polygon",
    "with_derived_faces",
]


def __getattr__(name: str) -> Any:
    return lazy_attribute(__name__, _HOMES, name)


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
