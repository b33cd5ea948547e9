"""Vectorized inverse kinematics along a path agrees with the closed form point by point."""

from __future__ import annotations

import numpy as np

from tooltransfer.tools.omni.ik import inverse_kinematics, joint_path
from tooltransfer.tools.omni.platform import OmniPlatform


def test_joint_path_matches_pointwise_ik() -> None:
    plat = OmniPlatform(a_t=0.028)
    pts = np.random.default_rng(0).uniform([-0.2, -0.05], [0.2, 0.25], (1500, 2))
    jp = joint_path(plat, pts)
    reachable = 0
    for p, q, vio, yaw in zip(pts, jp.q, jp.violation, jp.heading, strict=True):
        ik = inverse_kinematics(plat, p)
        if ik.reachable:
            reachable += 1
            assert vio == 0.0
            assert np.allclose(ik.q, q, atol=1e-12) and abs(ik.heading - yaw) < 1e-12
        else:
            assert vio > 0.0
    assert reachable > 300


def test_joint_path_is_continuous_along_a_continuous_path() -> None:
    plat = OmniPlatform()
    s = np.linspace(0, 1, 400)[:, None]
    pts = (1 - s) * np.array([0.08, 0.12]) + s * np.array([-0.08, 0.18])
    jp = joint_path(plat, pts)
    assert np.all(jp.violation == 0.0)
    assert np.abs(np.diff(jp.q, axis=0)).max() < 0.01
