"""A demonstrated switch: the learning input of the SS skill (paper section III.B, step 1).

During a switch the object rests; the tool leaves its first contact (tool point ``p_A`` on the
first face touching object point ``q_A``) and arrives at its second (``p_B`` touching ``q_B``).
The segmentation of recorded demonstrations (:mod:`tooltransfer.planner.learning.segmentation`) yields these; see
:mod:`tooltransfer.planner.learning.switch_dataset` for the conversion, and
:mod:`tooltransfer.planner.planning.ss.synthetic` for generated ones.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.omni.heading import rot
from tooltransfer.validation import check_array, check_positive, check_time


@dataclass(frozen=True)
class DemoSwitch:
    """One demonstrated switch (world frame, SI units).

    Attributes:
        t: shape (T,), strictly increasing times [s], T >= 5.
        xy: shape (T, 2), tool centre point positions (the tool reference) [m].
        yaw: shape (T,), tool headings [rad].
        tool_point_from, tool_point_to: shape (2,), ``p_A`` and ``p_B`` in the tool frame [m].
        object_point_from, object_point_to: shape (2,), ``q_A`` and ``q_B`` on the object (world) [m].
        centre: shape (2,), the resting object's centre [m].
        radius: the (disc) object's radius [m].
        face_from, face_to: face names (for labels; may be empty).
        name: where the switch comes from (for messages).
    """

    t: NDArray[np.float64]
    xy: NDArray[np.float64]
    yaw: NDArray[np.float64]
    tool_point_from: NDArray[np.float64]
    tool_point_to: NDArray[np.float64]
    object_point_from: NDArray[np.float64]
    object_point_to: NDArray[np.float64]
    centre: NDArray[np.float64]
    radius: float
    face_from: str = ""
    face_to: str = ""
    name: str = ""

    def __post_init__(self) -> None:
        w = f"{self.name}." if self.name else ""
        t = check_time(self.t, f"{w}t", min_len=5)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "xy", check_array(self.xy, f"{w}xy", shape=(t.size, 2)))
        object.__setattr__(self, "yaw", np.unwrap(check_array(self.yaw, f"{w}yaw", shape=(t.size,))))
        for f in ("tool_point_from", "tool_point_to", "object_point_from", "object_point_to", "centre"):
            object.__setattr__(self, f, check_array(getattr(self, f), f"{w}{f}", shape=(2,)))
        object.__setattr__(self, "radius", check_positive(self.radius, f"{w}radius"))
        if np.hypot(*(self.object_point_to - self.object_point_from)) < 1e-6 and np.hypot(
            *(self.tool_point_to - self.tool_point_from)
        ) < 1e-6:
            raise InputError(f"{w}contact points", "a switch that changes the contact", "the same contact twice")

    @property
    def duration(self) -> float:
        """Duration [s]."""
        return float(self.t[-1] - self.t[0])

    def contact_point_path(self) -> NDArray[np.float64]:
        """World path (T, 2) [m] of the tool's first contact point ``p_A`` (the paper's x, point 2)."""
        return self.xy + np.einsum("kij,j->ki", rot(self.yaw), self.tool_point_from)

    def tool_shift(self) -> NDArray[np.float64]:
        """The pure tool displacement ``-R_B (p_B - p_A)`` (2,) [m] at the final heading (eq. 9)."""
        return -rot(self.yaw[-1]) @ (self.tool_point_to - self.tool_point_from)

    def object_shift(self) -> NDArray[np.float64]:
        """The virtual object displacement ``q_B - q_A`` (2,) [m] (eq. 9)."""
        return self.object_point_to - self.object_point_from

    def winding(self) -> float:
        """Signed angle [rad] the contact point path turns about the object's centre (+: CCW)."""
        d = self.contact_point_path() - self.centre
        a = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
        return float(a[-1] - a[0])
