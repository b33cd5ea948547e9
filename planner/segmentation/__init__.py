"""Segmenting demonstrations into pushes and switches (DESIGN section 5, step 1): see
:mod:`planner.segmentation.core` for the method."""

from planner.segmentation.core import PushSegment, Segmentation, SwitchSegment, load_fixed_points, segment

__all__ = ["PushSegment", "Segmentation", "SwitchSegment", "load_fixed_points", "segment"]
