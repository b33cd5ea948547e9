"""Contact faces derived from a tool's outline (docs/design.md section 13).

* :func:`derive_faces` (:mod:`.faces`): every usable edge and vertex contact of an outline for a disc of
  a given radius and friction, and the planner faces (``edge_<i>``) they give.
* :func:`outline_from` (:mod:`.outline`): an outline from points, SVG path data, an SVG file or a tool file.
* :func:`derived_tool`, :func:`with_derived_faces`, :func:`match_faces` (:mod:`.tool`): tools with
  derived faces, and which derived face each hand-written face is.
* :func:`plot_derivation` (:mod:`.plot`, matplotlib): the outline with its contacts, normals and cones.
"""

from tooltransfer.tools.derive.contacts import EdgeContact, VertexContact
from tooltransfer.tools.derive.faces import (
    CONTACT_WINDOW,
    DEFAULT_C,
    DEFAULT_FRICTION,
    MAX_DERIVED_FACES,
    MIN_LENGTH,
    Derivation,
    derive_faces,
)
from tooltransfer.tools.derive.outline import ARC_TOLERANCE, SVG_SCALE, outline_from, svg_polygon
from tooltransfer.tools.derive.tool import MATCH_ANGLE, derived_tool, match_faces, with_derived_faces

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
