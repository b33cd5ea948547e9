"""The Phantom Omni with a fixed tool: DH kinematics (paper Table I), IK on the table, reach."""

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
