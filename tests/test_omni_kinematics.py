"""Omni kinematics: DH forward kinematics, Jacobian, and closed-form inverse kinematics."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tooltransfer.errors import InputError
from tooltransfer.tools.omni import (
    JointLimits,
    OmniPlatform,
    forward_kinematics,
    inverse_kinematics,
    jacobian,
    table_pose,
    tool_pose_world,
)
from tooltransfer.tools.omni.dh import D1, D_TOOL, L1, L2, THETA_TOOL, dh_transform

PLATFORM = OmniPlatform()
LO, HI = np.array(PLATFORM.limits.lower), np.array(PLATFORM.limits.upper)

joint_configs = st.tuples(*[st.floats(float(lo), float(hi)) for lo, hi in zip(LO, HI, strict=True)])


def test_dh_transform_is_rigid_and_matches_definition() -> None:
    T = dh_transform(0.3, 0.1, 0.2, -0.7)
    R = T[:3, :3]
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(R) == pytest.approx(1.0)
    # Rz(theta) Tz(d) Tx(a) Rx(alpha): translation (a cos theta, a sin theta, d)
    np.testing.assert_allclose(T[:3, 3], [0.1 * np.cos(-0.7), 0.1 * np.sin(-0.7), 0.2])


def test_fk_at_zero_matches_hand_computation() -> None:
    a_t = 0.026
    T = forward_kinematics([0.0, 0.0, 0.0], a_t)
    # frame 1: x1 = +x, y1 = -z, z1 = +y; arm stretched along x1, tool bent by 2pi/3 towards y1
    u = L1 + L2 + a_t * np.cos(THETA_TOOL)
    v = a_t * np.sin(THETA_TOOL)
    np.testing.assert_allclose(T[:3, 3], [u, D_TOOL, D1 - v], atol=1e-15)
    np.testing.assert_allclose(T[:3, 0], [np.cos(THETA_TOOL), 0.0, -np.sin(THETA_TOOL)], atol=1e-15)


@settings(derandomize=True, max_examples=300, deadline=None)
@given(joint_configs)
def test_fk_then_ik_round_trips(q: tuple[float, float, float]) -> None:
    T = forward_kinematics(q, PLATFORM.a_t)
    platform = replace(PLATFORM, table_height=float(T[2, 3]))  # pushing plane through the point
    target = platform.base_to_world(T[:3, 3])[:2]
    res = inverse_kinematics(platform, target, q_ref=q)
    assert res.reachable, res.detail
    assert res.q is not None
    p = tool_pose_world(platform, res.q)[:3, 3]
    assert np.linalg.norm(p - np.array([target[0], target[1], 0.0])) < 1e-9
    np.testing.assert_allclose(res.q, q, atol=1e-9)
    # every branch, valid or not, reaches the same point
    for b in res.branches:
        pb = tool_pose_world(platform, b.q)[:3, 3]
        assert np.linalg.norm(pb - np.array([target[0], target[1], 0.0])) < 1e-9


@settings(derandomize=True, max_examples=100, deadline=None)
@given(joint_configs)
def test_jacobian_matches_finite_differences(q: tuple[float, float, float]) -> None:
    a_t = 0.028
    J = jacobian(q, a_t)
    eps = 1e-6
    for i in range(3):
        dq = np.zeros(3)
        dq[i] = eps
        Tp, Tm = forward_kinematics(np.add(q, dq), a_t), forward_kinematics(np.subtract(q, dq), a_t)
        dp = (Tp[:3, 3] - Tm[:3, 3]) / (2 * eps)
        np.testing.assert_allclose(J[:3, i], dp, atol=1e-8)
        dR = (Tp[:3, :3] - Tm[:3, :3]) / (2 * eps)
        W = dR @ forward_kinematics(q, a_t)[:3, :3].T  # skew(omega)
        np.testing.assert_allclose(J[3:, i], [W[2, 1], W[0, 2], W[1, 0]], atol=1e-8)


def test_heading_follows_q1_and_table_pose() -> None:
    q = [0.3, 0.1, 1.0]
    x, y, yaw = table_pose(PLATFORM, q)
    assert yaw == pytest.approx(0.3)
    turned = replace(PLATFORM, base_yaw=0.0, base_xy=(0.1, -0.2))
    x2, y2, yaw2 = table_pose(turned, q)
    assert yaw2 == pytest.approx(0.3 - np.pi / 2)
    # rotating the base by -pi/2 and moving it moves the table point rigidly
    np.testing.assert_allclose([x2, y2], [y + 0.1, -x - 0.2], atol=1e-15)


def test_default_workspace_point_is_reachable_with_first_branch_elbow_up() -> None:
    res = inverse_kinematics(PLATFORM, [0.0, 0.15])
    assert res.reachable and res.q is not None and res.reason is None
    assert res.q[2] > 0.0
    assert len(res.branches) == 4
    assert res.heading == pytest.approx(res.q[0])


@pytest.mark.parametrize(
    ("point", "reason", "words"),
    [
        ([0.0, 0.40], "radius", "annulus"),
        ([0.0, 0.005], "radius", "tool offset"),
        ([0.2, 0.02], "angle", "waist"),
        ([0.0, 0.07], "joint limit", "joint(s)"),
    ],
)
def test_unreachable_targets_give_reason_not_nan(
    point: list[float], reason: str, words: str
) -> None:
    res = inverse_kinematics(PLATFORM, point)
    assert not res.reachable
    assert res.q is None and res.heading is None
    assert res.reason == reason
    assert words in res.detail
    for b in res.branches:
        assert np.all(np.isfinite(b.q)) and not b.within_limits


def test_ik_rejects_bad_input() -> None:
    with pytest.raises(InputError, match="point"):
        inverse_kinematics(PLATFORM, [0.0, np.nan])
    with pytest.raises(InputError, match="point"):
        inverse_kinematics(PLATFORM, [0.0, 0.1, 0.0])


def test_platform_validation() -> None:
    with pytest.raises(InputError, match="a_t"):
        OmniPlatform(a_t=-0.01)
    with pytest.raises(InputError, match="lower"):
        JointLimits(lower=(0.0, 0.0, 0.0), upper=(1.0, -1.0, 1.0))
    with pytest.raises(InputError, match="base_xy"):
        OmniPlatform(base_xy=(0.0, np.inf))


def test_world_base_round_trip() -> None:
    platform = OmniPlatform(base_xy=(0.05, -0.1), base_yaw=0.4, table_height=0.02)
    p = np.array([[0.1, 0.2, 0.0], [-0.3, 0.05, 0.1]])
    np.testing.assert_allclose(platform.base_to_world(platform.world_to_base(p)), p, atol=1e-15)
    T = platform.world_transform()
    np.testing.assert_allclose(
        (T[:3, :3] @ p[0] + T[:3, 3]), platform.base_to_world(p[0]), atol=1e-15
    )
