"""Checks of loaded recordings against what their dataset declares, before segmenting them.

:func:`tooltransfer.problems.dataset.load_dataset` checks the format and what needs no geometry (rates,
joint ranges, positions inside the Omni's reach). Here, for a demonstration loaded from files
(it carries its :class:`tooltransfer.problems.dataset.Origin`):

* **Kinematics.** The tool poses are the forward kinematics of the joints on the declared platform
  (the encoders give both): within :data:`FK_TOL` and :data:`YAW_TOL`, else the platform (``a_t``,
  ``base_xy``, ``base_yaw``) or the units are not those of the recording.
* **Contacts against the declared tool.** The object never lies inside the tool: the declared
  outline may not overlap the object (the camera track smoothed over half a second, the overlap's
  running median over half a second) by more than :data:`OVERLAP_TOL` (plus the camera noise above
  1.5 mm); and the object moves only when the tool touches it: while it moves, the median gap
  between the declared outline and the object stays within :data:`MOVING_GAP_TOL`. Both
  tolerances lie between what the committed demonstrations give with the tool they were recorded
  with and what they give with a wrong one declared (figures in ``benchmarks/README.md``).

Errors name the file (the CSV, or ``meta.yaml``'s ``tool`` field) and the row or the time.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import median_filter
from scipy.signal import savgol_filter

from tooltransfer.planner.learning.segmentation.geometry import ToolGeometry, table_poses, to_tool_frame
from tooltransfer.planner.learning.segmentation.rest import camera_noise
from tooltransfer.problems.dataset import DatasetError, Demonstration
from tooltransfer.tools.model import Tool
from tooltransfer.tools.pose import wrap_angle

FK_TOL, YAW_TOL = 0.002, 0.02
"""Tool pose against the joints' forward kinematics [m, rad]."""
OVERLAP_TOL = 0.003
"""Deepest sustained overlap [m] of the declared outline and the object (camera noise of 1.5 mm)."""
MOVING_GAP_TOL = 0.0015
"""Largest median gap [m] between the declared outline and the object while the object moves."""
MOVED = 0.006
"""The object moves at a camera sample when the smoothed track moves this much [m] within a second
around it."""


def _odd(t: NDArray[np.float64], window: float) -> int:
    return max(5, round(window / float(np.median(np.diff(t)))) // 2 * 2 + 1)


def check_recording(demo: Demonstration, tool: Tool) -> None:
    """Check a loaded demonstration's kinematics and contacts (module docstring); nothing for one made
    in memory (``demo.origin`` None).

    Raises:
        DatasetError: naming the file and the row (kinematics) or ``meta.yaml``'s ``tool`` (contacts).
    """
    o = demo.origin
    if o is None:
        return
    p = o.platform
    fk = table_poses(demo.joints, p.a_t, p.base_xy, p.base_yaw, p.table_height)
    pos = np.hypot(*(fk[:, :2] - demo.tool_pose[:, :2]).T)
    yaw = np.abs(wrap_angle(fk[:, 2] - demo.tool_pose[:, 2]))
    bad = (pos > FK_TOL) | (yaw > YAW_TOL)
    if bad.any():
        k = int(np.argmax(bad))
        raise DatasetError(o.csv, f"row {o.tool_rows[k]}, columns tool_x, tool_y, tool_yaw",
                           "the tool pose the joints q1, q2, q3 give (forward kinematics on meta.yaml's platform, "
                           f"within {1e3 * FK_TOL:g} mm and {YAW_TOL:g} rad)",
                           f"{1e3 * pos[k]:.3g} mm, {yaw[k]:.2g} rad off: ({demo.tool_pose[k, 0]:.4g}, "
                           f"{demo.tool_pose[k, 1]:.4g}, {demo.tool_pose[k, 2]:.4g}) vs ({fk[k, 0]:.4g}, "
                           f"{fk[k, 1]:.4g}, {fk[k, 2]:.4g})")
    t, t_o = demo.t_tool, demo.t_object
    if t_o.size < 7 or t.size < 7:
        return
    obj = savgol_filter(demo.object_xy, min(_odd(t_o, 0.5), t_o.size - (1 - t_o.size % 2)), 2, axis=0,
                        mode="interp")
    c = np.column_stack([np.interp(t, t_o, obj[:, j]) for j in range(2)])
    gap = ToolGeometry(tool, o.object_radius).outline_gap(to_tool_frame(c, demo.tool_pose))[0]
    excess = max(0.0, camera_noise(demo.object_xy) - 0.0015)
    run = median_filter(gap, size=min(_odd(t, 0.5), t.size), mode="nearest")
    k = int(np.argmin(run))
    name = o.csv.rsplit("/", 1)[-1]
    if run[k] < -(OVERLAP_TOL + excess):
        raise DatasetError(o.meta, "field tool", "the tool the recordings were made with (the object never inside "
                           "its outline)", f"{o.tool!r}: the object {1e3 * -run[k]:.1f} mm deep inside it at t = "
                           f"{t[k]:.2f} s of {name}")
    half = _odd(t_o, 1.0) // 2
    if t_o.size <= 2 * half:
        return
    moved = np.zeros(t_o.size, dtype=bool)
    moved[half:-half] = np.hypot(*(obj[2 * half:] - obj[:-2 * half]).T) > MOVED
    moving = np.interp(t, t_o, moved.astype(float)) > 0.5
    if moving.sum() < _odd(t, 0.5):
        return
    g = float(np.median(gap[moving]))
    if g > MOVING_GAP_TOL + 0.5 * excess:
        k = int(np.flatnonzero(moving)[0])
        raise DatasetError(o.meta, "field tool", "the tool the recordings were made with (touching the object "
                           "while it moves)", f"{o.tool!r}: {1e3 * g:.1f} mm from the object while it moves (median; "
                           f"from t = {t[k]:.2f} s of {name})")
