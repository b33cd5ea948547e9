"""Segmenting demonstrations into pushes and switches (docs/design.md section 5, step 1): see
:mod:`tooltransfer.planner.learning.segmentation.core` for the method.

The public names are imported on first use: the segmentation needs ``scipy.signal`` (and with it
``scipy.stats``), while :mod:`~tooltransfer.planner.learning.segmentation.geometry`, which checking a plan
file uses, needs only NumPy; importing that module must not load the rest.
"""

from typing import TYPE_CHECKING, Any

from tooltransfer.lazy import lazy_attribute

if TYPE_CHECKING:
    from tooltransfer.planner.learning.segmentation.core import PushSegment, Segmentation, SwitchSegment, segment
    from tooltransfer.planner.learning.segmentation.fixed_points import load_fixed_points

#: Each public name and its submodule.
_HOMES = {"PushSegment": "core", "Segmentation": "core", "SwitchSegment": "core", "segment": "core",
          "load_fixed_points": "fixed_points"}
__all__ = ["PushSegment", "Segmentation", "SwitchSegment", "load_fixed_points", "segment"]


def __getattr__(name: str) -> Any:
    return lazy_attribute(__name__, _HOMES, name)
