"""Tool and object geometry and the Phantom Omni arm.

* :mod:`tooltransfer.tools.model`: a :class:`Tool` is a planar outline in the tool frame [m] with named
  :class:`Face` s (push direction and cone half-angle ``theta_b`` [rad], contact range).
* :mod:`tooltransfer.tools.library`: tools as YAML files (``tools/library/*.yaml``); :func:`load_tool`.
* :mod:`tooltransfer.tools.derive`: the faces a round object can be pushed by, derived from an outline
  (:func:`derive_faces`); a tool file without faces gets them when loaded.
* :mod:`tooltransfer.tools.decompose`: exact, checked convex decomposition of an outline.
* :mod:`tooltransfer.tools.objects`: the pushed object (disc of radius 17.5 mm by default) and obstacles.
* :mod:`tooltransfer.tools.contact`: tool poses putting a face in contact with the object.
* :mod:`tooltransfer.tools.clearance`: clearance and penetration depth, static and swept.
* :mod:`tooltransfer.tools.omni`: DH kinematics, inverse kinematics and reachable region of the Omni.
* :mod:`tooltransfer.tools.sim`: the Omni with a tool, the puck and obstacles in MuJoCo (imported on demand).

Frames and units follow docs/design.md section 2: SI units, world frame in the table plane with the
origin under the Omni's first joint axis, x right, y forward, z up.

The public names are imported on first use (their modules bring numpy, shapely and yaml): importing
one submodule, as checking or exporting a plan does, loads that module and what it imports, not the
rest of the package. ``clearance`` is both a submodule and a function; the package's name is the
function, as it was when the names were imported eagerly.
"""

import sys
from types import ModuleType
from typing import TYPE_CHECKING, Any

from tooltransfer.lazy import lazy_attribute

if TYPE_CHECKING:
    from tooltransfer.tools.clearance import (
        clearance,
        penetration_depth,
        signed_distance,
        swept_clearance,
        swept_penetration_depth,
        tool_polygon,
    )
    from tooltransfer.tools.contact import Contact, PlatformContact, contact_on_platform, contact_pose
    from tooltransfer.tools.decompose import convex_decomposition
    from tooltransfer.tools.derive import derive_faces
    from tooltransfer.tools.errors import ToolSpecError, UnknownFaceError, UnknownToolError
    from tooltransfer.tools.library import (
        dump_tool,
        library_names,
        load_library,
        load_tool,
        tool_from_dict,
        tool_to_dict,
    )
    from tooltransfer.tools.model import Face, Tool
    from tooltransfer.tools.objects import OBJECT_RADIUS, Disc, DiscObject, PolygonObject
    from tooltransfer.tools.pose import Pose2D

#: Each public name and its submodule.
_HOMES = {
    "clearance": "clearance", "penetration_depth": "clearance", "signed_distance": "clearance",
    "swept_clearance": "clearance", "swept_penetration_depth": "clearance", "tool_polygon": "clearance",
    "Contact": "contact", "PlatformContact": "contact", "contact_on_platform": "contact", "contact_pose": "contact",
    "convex_decomposition": "decompose", "derive_faces": "derive",
    "ToolSpecError": "errors", "UnknownFaceError": "errors", "UnknownToolError": "errors",
    "dump_tool": "library", "library_names": "library", "load_library": "library", "load_tool": "library",
    "tool_from_dict": "library", "tool_to_dict": "library", "Face": "model", "Tool": "model",
    "OBJECT_RADIUS": "objects", "Disc": "objects", "DiscObject": "objects", "PolygonObject": "objects",
    "Pose2D": "pose",
}

__all__ = [
    "OBJECT_RADIUS",
    "Contact",
    "Disc",
    "DiscObject",
    "Face",
    "PlatformContact",
    "PolygonObject",
    "Pose2D",
    "Tool",
    "ToolSpecError",
    "UnknownFaceError",
    "UnknownToolError",
    "clearance",
    "contact_on_platform",
    "contact_pose",
    "convex_decomposition",
    "derive_faces",
    "dump_tool",
    "library_names",
    "load_library",
    "load_tool",
    "penetration_depth",
    "signed_distance",
    "swept_clearance",
    "swept_penetration_depth",
    "tool_from_dict",
    "tool_polygon",
    "tool_to_dict",
]


def __getattr__(name: str) -> Any:
    return lazy_attribute(__name__, _HOMES, name)


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])


class _Package(ModuleType):
    """The package's module type: importing the submodule ``clearance`` binds that name in the
    package (the import system sets it), which would hide the function :func:`clearance`; the
    binding is skipped, and the name stays the function (imported by :func:`__getattr__`)."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "clearance" and isinstance(value, ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
