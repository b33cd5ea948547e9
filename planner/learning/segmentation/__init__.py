"""Segmenting demonstrations into pushes and switches (docs/design.md section 5, step 1): see
:mod:`tooltransfer.planner.learning.segmentation.core` for the method."""

from tooltransfer.planner.learning.segmentation.core import PushSegment, Segmentation, SwitchSegment, segment
from tooltransfer.planner.learning.segmentation.fixed_points import load_fixed_points

__all__ = ["PushSegment", "Segmentation", "SwitchSegment", "load_fixed_points", "segment"]
