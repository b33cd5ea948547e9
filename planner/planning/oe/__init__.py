"""OE skill condensing for a new tool (docs/design.md section 5): push plans, the ``qp`` variant, metrics."""

from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.oe.push_plan import Push, PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.qp_variant import condense_qp

__all__ = ["FaceFrame", "Push", "PushPlan", "QPOptions", "condense_qp"]
