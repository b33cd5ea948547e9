"""Joint references for the PD actuators: a sampled joint path resampled on the physics steps, and a
tool path turned into one through the Omni's inverse kinematics."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.omni.ik import inverse_kinematics, joint_path
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.validation import check_array, check_time

#: Tolerance [rad] on the joint limits for a reference (the planner's paths touch them).
LIMIT_TOL = 1e-6


class JointReference(NamedTuple):
    """The reference of each physics step: ``q`` (n, 3) [rad] and ``qd`` (n, 3) [rad/s] at the step
    times ``t[0] + i * dt``, ``i = 0 .. n - 1``, with ``n = round((t[-1] - t[0]) / dt)``."""

    q: NDArray[np.float64]
    qd: NDArray[np.float64]


def joint_reference(
    t: ArrayLike, q: ArrayLike, qd: ArrayLike | None, dt: float, platform: OmniPlatform
) -> JointReference:
    """Resample a joint path on the physics steps.

    Args:
        t: shape (T,), increasing sample times [s] (only differences matter).
        q: shape (T, 3), joints [rad], inside the platform's limits (within :data:`LIMIT_TOL`).
        qd: shape (T, 3), joint velocities [rad/s], or None for finite differences of ``q``.
        dt: physics step [s]. platform: gives the joint limits.

    Raises:
        InputError: naming the argument (and the sample) that is malformed or outside the limits.
    """
    tt = check_time(t, "t", min_len=2)
    qq = check_array(q, "q", shape=(tt.size, 3))
    qv = np.gradient(qq, tt, axis=0) if qd is None else check_array(qd, "qd", shape=(tt.size, 3))
    lo, hi = np.asarray(platform.limits.lower), np.asarray(platform.limits.upper)
    bad = np.flatnonzero(((qq < lo - LIMIT_TOL) | (qq > hi + LIMIT_TOL)).any(axis=1))
    if bad.size:
        k = int(bad[0])
        raise InputError(f"q[{k}]", f"joints within the limits [{lo.tolist()}, {hi.tolist()}] rad",
                         f"{qq[k].tolist()} at t = {tt[k]:.4g} s")
    n = round((tt[-1] - tt[0]) / dt)
    if n < 1:
        raise InputError("t", f"a duration of at least one physics step ({dt} s)", f"{tt[-1] - tt[0]:.3g} s")
    ts = tt[0] + dt * np.arange(n)
    return JointReference(
        np.column_stack([np.interp(ts, tt, qq[:, j]) for j in range(3)]),
        np.column_stack([np.interp(ts, tt, qv[:, j]) for j in range(3)]),
    )


def tool_path_joints(platform: OmniPlatform, tool_xy: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """Joints (T, 3) [rad] placing the tool centre point on ``tool_xy`` (T, 2) [m] (world, table
    plane) at the times ``t`` (T,) [s], one inverse-kinematics branch throughout
    (:func:`tooltransfer.tools.omni.ik.joint_path`); the tool's heading is then the one q1 gives.

    Raises:
        InputError: naming the first sample the Omni cannot reach within its joint limits, and why.
    """
    tt = check_time(t, "t", min_len=2)
    xy = check_array(tool_xy, "tool_xy", shape=(tt.size, 2))
    jp = joint_path(platform, xy)
    bad = np.flatnonzero(~(jp.violation <= 0.0))
    if bad.size:
        k = int(bad[0])
        ik = inverse_kinematics(platform, xy[k])
        why = ik.detail if not ik.reachable else (
            f"the path's inverse-kinematics branch leaves the joint limits by {jp.violation[k]:.3g} rad there")
        raise InputError(f"tool_xy[{k}]", "a point the Omni reaches within its joint limits",
                         f"{xy[k].tolist()} at t = {tt[k]:.4g} s ({why})")
    return jp.q
