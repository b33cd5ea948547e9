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
"""

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
