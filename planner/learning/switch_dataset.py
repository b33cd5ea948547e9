"""From the segmentation of recorded demonstrations (:mod:`tooltransfer.planner.learning.segmentation`) to the SS
skill's input: one :class:`~tooltransfer.planner.learning.demo_switch.DemoSwitch` per switch segment.

A switch segment gives its time span and the contact points (tool frame and world) where the first
face leaves and the second arrives; the tool track inside the span (encoder samples: tool centre
point and heading) is the demonstrated motion, and the object rests where the push before it left it.
"""

from __future__ import annotations

from pathlib import Path

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.demo_switch import DemoSwitch
from tooltransfer.problems import FINGER_DEMOS
from tooltransfer.problems.dataset import Demonstration


def demo_switches(demo: Demonstration, segmentation: object, radius: float,
                  faces: tuple[str, str] | None = None, min_samples: int = 5) -> list[DemoSwitch]:
    """The switches of one segmented demonstration (optionally only those from ``faces[0]`` to
    ``faces[1]``); segments with fewer than ``min_samples`` tool samples are skipped.

    Args:
        demo: the recordings; segmentation: its :class:`tooltransfer.planner.learning.segmentation.Segmentation`;
        radius: the object's radius [m].
    """
    out = []
    pushes = list(segmentation.pushes)  # type: ignore[attr-defined]
    for i, sw in enumerate(segmentation.switches):  # type: ignore[attr-defined]
        if faces is not None and (sw.face_from, sw.face_to) != tuple(faces):
            continue
        before = [p for p in pushes if abs(p.t_end - sw.t_start) < 1e-9]
        if not before:
            raise InputError(f"{demo.name}.switches[{i}]", "a switch that starts where a push ends")
        m = (demo.t_tool >= sw.t_start) & (demo.t_tool <= sw.t_end)
        if int(m.sum()) < min_samples:
            continue
        pose = demo.tool_pose[m]
        out.append(DemoSwitch(
            t=demo.t_tool[m], xy=pose[:, :2], yaw=pose[:, 2], tool_point_from=sw.tool_point_from,
            tool_point_to=sw.tool_point_to, object_point_from=sw.object_point_from,
            object_point_to=sw.object_point_to, centre=before[0].object_after, radius=radius,
            face_from=sw.face_from, face_to=sw.face_to, name=f"{demo.name}.switch{i}",
        ))
    return out


def dataset_switches(folder: str | Path, faces: tuple[str, str] | None = ("upper", "left")) -> list[DemoSwitch]:
    """Load a dataset (:func:`tooltransfer.problems.dataset.load_dataset`), segment every demonstration with its
    tool, and return its switches (from ``faces[0]`` to ``faces[1]``; None: all), in order."""
    from tooltransfer.planner.learning.segmentation import segment
    from tooltransfer.problems.dataset import load_dataset

    ds = load_dataset(folder)
    tool = ds.tool()
    radius = float(ds.meta.object_radius)
    out: list[DemoSwitch] = []
    for d in ds.demonstrations:
        out += demo_switches(d, segment(d, tool, radius=radius), radius, faces)
    return out


def default_dataset() -> Path:
    """The committed default dataset's folder (tool 1's demonstrations)."""
    return FINGER_DEMOS
