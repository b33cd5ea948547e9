"""Standard Denavit-Hartenberg kinematics of the Phantom Omni with a tool (paper Table I).

Each row gives ``T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. Lengths in metres, angles in
radians (the paper prints the table in mm and labels alpha in mm; alpha is in radians):

===== ========= ========= ========= ==============
joint alpha     a         d         theta
===== ========= ========= ========= ==============
1     -pi/2     0         0.13335   q1
2     0         0.13335   0         q2
3     0         0.13335   0         q3
tool  0         a_t       0.010     2 pi/3 (fixed)
===== ========= ========= ========= ==============

The last three Omni joints are fixed, so after joint 1 the arm moves in a vertical plane:
frame 1 has ``x1`` horizontal along the arm, ``y1`` pointing down and ``z1`` horizontal, and
joints 2, 3 rotate about ``z1``. The tool row's ``d = 10 mm`` offsets the tool centre point
sideways (along ``z1``) out of that plane.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.validation import check_array

#: Shoulder height above the base frame origin, d1 [m] (Table I).
D1 = 0.13335
#: Upper-arm length a2 [m] (Table I).
L1 = 0.13335
#: Forearm length a3 [m] (Table I).
L2 = 0.13335
#: Tool row offset d_t [m] (Table I).
D_TOOL = 0.010
#: Fixed tool row angle [rad] (Table I).
THETA_TOOL = 2.0 * np.pi / 3.0


def dh_transform(alpha: float, a: float, d: float, theta: float) -> NDArray[np.float64]:
    """Standard DH link transform ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``, shape (4, 4), lengths [m]."""
    ca, sa = np.cos(alpha), np.sin(alpha)
    ct, st = np.cos(theta), np.sin(theta)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_table(q: ArrayLike, a_t: float) -> NDArray[np.float64]:
    """The DH rows ``(alpha, a, d, theta)`` for joints ``q`` (3,) [rad] and tool length ``a_t`` [m].

    Returns:
        shape (4, 4): one row per link (three joints, then the tool).
    """
    q1, q2, q3 = np.asarray(q, dtype=np.float64)
    return np.array(
        [
            [-np.pi / 2, 0.0, D1, q1],
            [0.0, L1, 0.0, q2],
            [0.0, L2, 0.0, q3],
            [0.0, a_t, D_TOOL, THETA_TOOL],
        ]
    )


def link_frames(q: ArrayLike, a_t: float) -> list[NDArray[np.float64]]:
    """Poses of frames 1, 2, 3 and the tool frame in the base frame, each shape (4, 4) [m]."""
    qv = check_array(q, "q", shape=(3,))
    frames = []
    T = np.eye(4)
    for alpha, a, d, theta in dh_table(qv, a_t):
        T = T @ dh_transform(alpha, a, d, theta)
        frames.append(T)
    return frames


def forward_kinematics(q: ArrayLike, a_t: float) -> NDArray[np.float64]:
    """Pose of the tool frame in the Omni base frame, shape (4, 4), translation in metres.

    Args:
        q: joint angles ``(q1, q2, q3)`` [rad], shape (3,).
        a_t: tool length a_t [m] (Table I, tool row; Table II gives 0.026 for tool 1).
    """
    return link_frames(q, a_t)[-1]


def jacobian(q: ArrayLike, a_t: float) -> NDArray[np.float64]:
    """Geometric Jacobian of the tool frame in the base frame, shape (6, 3).

    Rows 0-2 map joint rates [rad/s] to the tool centre point's linear velocity [m/s]; rows 3-5
    to the tool frame's angular velocity [rad/s]. All joints are revolute about the ``z`` axis
    of the preceding frame.
    """
    frames = link_frames(q, a_t)
    p_tool = frames[-1][:3, 3]
    J = np.zeros((6, 3))
    previous = [np.eye(4), frames[0], frames[1]]
    for i, T in enumerate(previous):
        z, o = T[:3, 2], T[:3, 3]
        J[:3, i] = np.cross(z, p_tool - o)
        J[3:, i] = z
    return J
