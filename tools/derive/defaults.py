"""The derivation's default settings, in a module of their own (no numpy, no shapely): the command
line's ``tools derive`` options show them in their help, and building the parser imports this alone.
:mod:`.faces` and :mod:`.outline` use them under the same names."""

#: Default tool-object friction coefficient (the platform's nominal ``mu``,
#: :class:`tooltransfer.tools.pushing.mechanics.PushMechanics`).
DEFAULT_FRICTION = 0.8
#: Default limit-surface ratio ``c`` (sets the sideways travel one contact carries).
DEFAULT_C = 0.59
#: Shortest usable part [m] of an edge that makes a face: room for the contact to roll while the
#: object moves sideways by ``MIN_LENGTH c^2`` (0.7 mm at c = 0.59).
MIN_LENGTH = 0.002
#: Most derived faces (see :mod:`tooltransfer.tools.derive.faces`).
MAX_DERIVED_FACES = 8
#: Longest contact range [m] of a derived face (the task schema's default ``oe.contact_span``).
CONTACT_WINDOW = 0.012
#: Default largest distance [m] between an SVG curve or arc and the chords replacing it (0.1 mm).
ARC_TOLERANCE = 1e-4
#: Default metres per SVG unit (millimetres).
SVG_SCALE = 1e-3

__all__ = ["ARC_TOLERANCE", "CONTACT_WINDOW", "DEFAULT_C", "DEFAULT_FRICTION", "MAX_DERIVED_FACES", "MIN_LENGTH",
           "SVG_SCALE"]
