"""Clearance and penetration depth between a tool and discs or polygons, at a pose and swept."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from tooltransfer.errors import InputError
from tooltransfer.tools import (
    Disc,
    Pose2D,
    clearance,
    load_tool,
    penetration_depth,
    signed_distance,
    swept_clearance,
    swept_penetration_depth,
    tool_polygon,
)
from tooltransfer.tools.clearance import swept_pieces

I_SHAPE = load_tool("i_shape")  # box x in [-6, 6] mm, y in [-30, 10] mm
L_SHAPE = load_tool("l_shape")


def test_disc_clearance_and_depth_known_values() -> None:
    pose = Pose2D(0.0, 0.0, 0.0)
    apart = Disc([0.006 + 0.0175 + 0.003, 0.0], 0.0175)
    assert clearance(I_SHAPE, pose, apart) == pytest.approx(0.003, abs=1e-15)
    assert penetration_depth(I_SHAPE, pose, apart) == 0.0
    overlap = Disc([0.006 + 0.0175 - 0.002, 0.0], 0.0175)
    assert clearance(I_SHAPE, pose, overlap) == 0.0
    assert penetration_depth(I_SHAPE, pose, overlap) == pytest.approx(0.002, abs=1e-15)
    assert signed_distance(I_SHAPE, pose, overlap) == pytest.approx(-0.002, abs=1e-15)
    # centre inside the tool: depth is R plus the distance to the boundary
    inside = Disc([0.0, 0.0], 0.0175)
    assert penetration_depth(I_SHAPE, pose, inside) == pytest.approx(0.0175 + 0.006)


def test_polygon_depth_is_the_minimum_translation_for_convex_shapes() -> None:
    pose = Pose2D(0.0, 0.0, 0.0)
    box = shapely.box(0.004, -0.01, 0.03, 0.0)  # overlaps the bar's right side by 2 mm
    assert penetration_depth(I_SHAPE, pose, box) == pytest.approx(0.002, abs=1e-15)
    assert clearance(I_SHAPE, pose, box) == 0.0
    far = shapely.box(0.009, -0.01, 0.03, 0.0)
    assert clearance(I_SHAPE, pose, far) == pytest.approx(0.003, abs=1e-15)
    assert signed_distance(I_SHAPE, pose, far) == pytest.approx(0.003, abs=1e-15)
    assert signed_distance(I_SHAPE, pose, box) == pytest.approx(-0.002, abs=1e-15)


def test_non_convex_tool_uses_its_pieces() -> None:
    # a disc in the L's inner corner, clear of both arms: the hull would report an overlap
    pose = Pose2D(0.0, 0.0, 0.0)
    d = Disc([0.006 + 0.005 + 0.001, 0.002 + 0.005 + 0.001], 0.005)
    assert L_SHAPE.outline.convex_hull.contains(shapely.Point(d.centre))
    assert clearance(L_SHAPE, pose, d) == pytest.approx(0.001, abs=1e-15)
    assert penetration_depth(L_SHAPE, pose, d) == 0.0


@settings(derandomize=True, max_examples=80, deadline=None)
@given(
    x=st.floats(-0.05, 0.05),
    y=st.floats(-0.05, 0.05),
    yaw=st.floats(-3.0, 3.0),
    cx=st.floats(-0.06, 0.06),
    cy=st.floats(-0.06, 0.06),
    r=st.floats(0.002, 0.03),
)
def test_disc_measures_agree_with_shapely(
    x: float, y: float, yaw: float, cx: float, cy: float, r: float
) -> None:
    pose = Pose2D(x, y, yaw)
    disc = Disc([cx, cy], r)
    poly = tool_polygon(L_SHAPE, pose)
    pt = shapely.Point(cx, cy)
    gap = poly.distance(pt) - r
    assert clearance(L_SHAPE, pose, disc) == pytest.approx(max(gap, 0.0), abs=1e-12)
    overlaps = poly.intersects(disc.polygon(256))
    assert (penetration_depth(L_SHAPE, pose, disc) > 1e-6) <= overlaps
    sd = signed_distance(L_SHAPE, pose, disc)
    assert np.sign(round(sd, 9)) != 1 or not poly.buffer(r - 1e-9).contains(pt)


def test_swept_translation_detects_a_pass_through() -> None:
    obstacle = Disc([0.0, 0.05], 0.005)
    start, end = Pose2D(-0.05, 0.05, 0.0), Pose2D(0.05, 0.05, 0.0)
    assert clearance(I_SHAPE, start, obstacle) > 0.02
    assert clearance(I_SHAPE, end, obstacle) > 0.02
    assert swept_clearance(I_SHAPE, start, end, obstacle) == 0.0
    assert swept_penetration_depth(I_SHAPE, start, end, obstacle) > 0.005
    # parallel motion 2 mm beside the obstacle: exact clearance for a pure translation
    beside = Disc([0.0, 0.05 + 0.010 + 0.002 + 0.005], 0.005)  # bar top at y = 60 mm
    assert swept_clearance(I_SHAPE, start, end, beside) == pytest.approx(0.002, abs=1e-12)
    assert swept_penetration_depth(I_SHAPE, start, end, beside) == 0.0


@pytest.mark.parametrize("dyaw", [0.3, 1.0, -2.0])
def test_swept_rotation_is_a_tight_lower_bound(dyaw: float) -> None:
    tol = 1e-5
    start, end = Pose2D(0.0, 0.0, 0.1), Pose2D(0.01, 0.02, 0.1 + dyaw)
    obstacle = Disc([0.03, 0.03], 0.004)
    lower = swept_clearance(L_SHAPE, start, end, obstacle, tol=tol)
    dense = min(
        clearance(L_SHAPE, start.interpolate(end, t), obstacle) for t in np.linspace(0, 1, 4001)
    )
    assert lower <= dense + 1e-12
    assert dense - lower <= tol + 1e-6  # sampling at 4001 points is itself within ~1e-6
    # the swept region contains every sampled pose of the tool
    region = shapely.unary_union(swept_pieces(L_SHAPE, start, end, tol)).buffer(1e-12)
    for t in np.linspace(0, 1, 37):
        assert region.contains(tool_polygon(L_SHAPE, start.interpolate(end, t)))


def test_bad_inputs() -> None:
    with pytest.raises(InputError, match="other"):
        clearance(I_SHAPE, Pose2D(0, 0, 0), "disc")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="yaw"):
        Pose2D(0.0, 0.0, float("nan"))
    with pytest.raises(InputError, match="tol"):
        swept_clearance(I_SHAPE, Pose2D(0, 0, 0), Pose2D(0, 0, 1), Disc([0, 0.1], 0.01), tol=-1.0)
