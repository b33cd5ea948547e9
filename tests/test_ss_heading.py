"""The tool centre path under the Omni's heading: Newton's inverse of the point path."""

from __future__ import annotations

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st

from tooltransfer.tools.omni.heading import centre_path, heading, point_path
from tooltransfer.tools.omni.platform import OmniPlatform

PLATFORM = OmniPlatform()


@settings(max_examples=50, deadline=None, derandomize=True)
# found by hypothesis 6.100 (make test-lowest): a target near the base, where a full Newton step from
# c = x - p jumped past the root and the undamped iteration returned a centre 74 mm off
@example(r=0.11001586914062514, th=2.15625, px=0.0, py=0.05999779701232916)
@given(
    r=st.floats(0.11, 0.22), th=st.floats(np.pi / 2 - 0.6, np.pi / 2 + 0.6),
    px=st.floats(-0.04, 0.04), py=st.floats(-0.06, 0.06),
)
def test_centre_path_inverts_point_path(r: float, th: float, px: float, py: float) -> None:
    """Across the reach, for tool-frame points up to 72 mm from the centre: the tool-frame point of
    the returned centres lands on the targets to 1e-12 m, with the Omni's heading there."""
    s = np.linspace(-0.02, 0.02, 7)
    x = np.column_stack([r * np.cos(th) + s, r * np.sin(th) - s])
    c = centre_path(PLATFORM, x, [px, py])
    np.testing.assert_allclose(point_path(PLATFORM, c, [px, py]), x, rtol=0, atol=1e-12)
    yaw = heading(PLATFORM, c)
    rot = np.stack([np.stack([np.cos(yaw), -np.sin(yaw)], -1), np.stack([np.sin(yaw), np.cos(yaw)], -1)], -2)
    np.testing.assert_allclose(c + rot @ np.array([px, py]), x, rtol=0, atol=1e-12)
