"""The Phantom Omni with a fixed tool: DH kinematics (paper Table I), IK on the table, reach.

The names are imported on first use: checking a plan needs :mod:`.platform` and :mod:`.dh`, not the
inverse kinematics and the reach (shapely).
"""

from typing import TYPE_CHECKING, Any

from tooltransfer.lazy import lazy_attribute

if TYPE_CHECKING:
    from tooltransfer.tools.omni.dh import dh_transform, forward_kinematics, jacobian
    from tooltransfer.tools.omni.ik import IKBranch, IKResult, inverse_kinematics, table_pose, tool_pose_world
    from tooltransfer.tools.omni.platform import DEFAULT_LIMITS, JointLimits, OmniPlatform
    from tooltransfer.tools.omni.reach import (
        LinearRows,
        ReachSector,
        inner_row,
        outer_rows,
        reach_sector,
        reachable_polygon,
        stack_rows,
        wedge_rows,
    )

#: Each public name and its submodule.
_HOMES = {
    "dh_transform": "dh", "forward_kinematics": "dh", "jacobian": "dh", "IKBranch": "ik", "IKResult": "ik",
    "inverse_kinematics": "ik", "table_pose": "ik", "tool_pose_world": "ik", "DEFAULT_LIMITS": "platform",
    "JointLimits": "platform", "OmniPlatform": "platform", "LinearRows": "reach", "ReachSector": "reach",
    "inner_row": "reach", "outer_rows": "reach", "reach_sector": "reach", "reachable_polygon": "reach",
    "stack_rows": "reach", "wedge_rows": "reach"
}

__all__ = [
    "DEFAULT_LIMITS",
    "IKBranch",
    "IKResult",
    "JointLimits",
    "LinearRows",
    "OmniPlatform",
    "ReachSector",
    "dh_transform",
    "forward_kinematics",
    "inner_row",
    "inverse_kinematics",
    "jacobian",
    "outer_rows",
    "reach_sector",
    "reachable_polygon",
    "stack_rows",
    "table_pose",
    "tool_pose_world",
    "wedge_rows",
]


def __getattr__(name: str) -> Any:
    return lazy_attribute(__name__, _HOMES, name)


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
