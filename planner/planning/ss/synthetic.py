"""Synthetic demonstrated switches, for tests and examples without recorded data.

Tool 1 (the finger) switches from its ``upper`` face touching the bottom of the puck to its
``left`` face touching the puck's right side, as in the paper's Fig. 9: the geometric switch path of
:func:`tooltransfer.planner.planning.ss.arch_variant.switch_path` (back off, arch round the puck, approach), timed by a
minimum-jerk profile along its length, with a smooth hand tremor (low-pass filtered noise, zero at the two
contacts) on top. The heading follows the Omni's waist; contact points come from
:func:`tooltransfer.tools.contact.contact_on_platform`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InfeasibleError, InputError
from tooltransfer.planner.learning.demo_switch import DemoSwitch
from tooltransfer.planner.learning.virtual_motion import min_jerk
from tooltransfer.planner.planning.ss.arch_variant import switch_path
from tooltransfer.tools.contact import Contact, contact_on_platform
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.model import Tool
from tooltransfer.tools.objects import OBJECT_RADIUS
from tooltransfer.tools.omni.heading import heading
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.validation import check_array, check_positive


def platform_contact(tool: Tool, face: str, centre: NDArray[np.float64], platform: OmniPlatform,
                     s: float | None = None) -> Contact:
    """Contact pose of ``face`` on the disc at ``centre`` with the Omni's heading; raises
    :class:`InfeasibleError` when the Omni cannot reach it."""
    f = tool.face(face)
    direction = float(heading(platform, centre)[0]) + f.push_angle
    pc = contact_on_platform(tool, face, centre, direction, platform, s=s)
    if pc.contact is None:
        raise InfeasibleError("switch contact", ["reach"], f"face {face!r} at {np.round(centre, 4).tolist()}: "
                              f"{pc.ik.reason} ({pc.ik.detail})")
    return pc.contact


def _tremor(rng: np.random.Generator, n: int, amplitude: float, width: int) -> NDArray[np.float64]:
    """Smooth noise (n, 2) of RMS about ``amplitude`` [m] (Gaussian-filtered over ``width`` samples)."""
    raw = rng.standard_normal((n + 6 * width, 2))
    k = np.exp(-0.5 * (np.arange(-3 * width, 3 * width + 1) / width) ** 2)
    sm = np.column_stack([np.convolve(raw[:, j], k / k.sum(), mode="valid") for j in range(2)])[:n]
    return amplitude * sm / max(float(np.std(sm)), 1e-12)


def synthetic_switches(
    n: int = 5,
    *,
    seed: int = 0,
    centre: ArrayLike = (0.0, 0.16),
    spread: float = 0.01,
    tremor: float = 3e-4,
    duration: float = 1.5,
    rate: float = 100.0,
    faces: tuple[str, str] = ("upper", "left"),
    tool: Tool | None = None,
    platform: OmniPlatform | None = None,
) -> list[DemoSwitch]:
    """``n`` demonstrated switches of tool 1 (module docstring), seeded.

    Args:
        n: number of switches; seed: random seed.
        centre: shape (2,), mean object centre [m]; spread: uniform jitter of it per switch [m].
        tremor: RMS of the smooth tremor [m]; duration: mean duration [s] (+-10 %); rate: samples/s.
        faces: the first and second face; tool: default the library's ``finger``;
        platform: default the Omni carrying that tool.
    """
    if not isinstance(n, int) or n < 1:
        raise InputError("n", "an integer >= 1", repr(n))
    c0 = check_array(centre, "centre", shape=(2,))
    duration, rate = check_positive(duration, "duration"), check_positive(rate, "rate")
    tool = tool or load_tool("finger")
    platform = platform or OmniPlatform(a_t=tool.a_t)
    rng = np.random.default_rng(seed)
    out = []
    for j in range(n):
        c = c0 + rng.uniform(-spread, spread, 2)
        ranges = [tool.face(f).contact_range for f in faces]
        ss = [float(rng.uniform(lo + 0.2 * (hi - lo), hi - 0.2 * (hi - lo))) for lo, hi in ranges]
        a, b = (platform_contact(tool, f, c, platform, s) for f, s in zip(faces, ss, strict=True))
        dir_a = a.pose.yaw + tool.face(faces[0]).push_angle
        dir_b = b.pose.yaw + tool.face(faces[1]).push_angle
        path = switch_path(tool, platform, c, np.array([a.pose.x, a.pose.y]), dir_a,
                           np.array([b.pose.x, b.pose.y]), dir_b)
        arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
        tj = duration * rng.uniform(0.9, 1.1)
        t = np.arange(0.0, tj + 0.5 / rate, 1.0 / rate)
        t[-1] = tj
        where = min_jerk(t / tj) * arc[-1]
        xy = np.column_stack([np.interp(where, arc, path[:, k]) for k in range(2)])
        xy += np.sin(np.pi * t / tj)[:, None] ** 2 * _tremor(rng, t.size, tremor, max(2, int(0.05 * rate)))
        out.append(DemoSwitch(
            t=t, xy=xy, yaw=heading(platform, xy), tool_point_from=a.tool_point, tool_point_to=b.tool_point,
            object_point_from=a.object_point, object_point_to=b.object_point, centre=c, radius=OBJECT_RADIUS,
            face_from=faces[0], face_to=faces[1], name=f"synthetic_{j}",
        ))
    return out
