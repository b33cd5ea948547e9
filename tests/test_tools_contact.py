"""Contact poses: the face touches the object exactly, without penetration, pushing in its cone."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from tooltransfer.errors import InputError
from tooltransfer.tools import (
    OBJECT_RADIUS,
    Disc,
    DiscObject,
    PolygonObject,
    contact_on_platform,
    contact_pose,
    load_library,
    load_tool,
    penetration_depth,
    signed_distance,
    tool_polygon,
)
from tooltransfer.tools.omni import OmniPlatform, inverse_kinematics

LIBRARY = load_library()
FACES = [(t, f.name) for t, tool in sorted(LIBRARY.items()) for f in tool.faces]


def _face_world(tool, contact):
    f = tool.face(contact.face)
    return contact.pose.apply(f.start), contact.pose.apply(f.end)


def _dist_point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    return float(np.linalg.norm(p - (a + t * (b - a))))


@pytest.mark.parametrize(("tool_name", "face"), FACES)
@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    cx=st.floats(-0.2, 0.2),
    cy=st.floats(0.0, 0.3),
    direction=st.floats(-np.pi, np.pi),
    s=st.floats(0.0, 1.0),
)
def test_contact_is_exact_and_penetration_free(
    tool_name: str, face: str, cx: float, cy: float, direction: float, s: float
) -> None:
    tool = LIBRARY[tool_name]
    f = tool.face(face)
    s0, s1 = f.contact_range
    frac = s0 + s * (s1 - s0)
    centre = np.array([cx, cy])
    c = contact_pose(tool, face, centre, direction, s=frac)
    a, b = _face_world(tool, c)
    # the face's line is tangent to the object: centre at exactly R from it, on the outer side
    assert _dist_point_segment(centre, a, b) == pytest.approx(OBJECT_RADIUS, abs=1e-9)
    assert (centre - a) @ c.normal == pytest.approx(OBJECT_RADIUS, abs=1e-9)
    # the contact point is on the object boundary, on the face, and is the tool point
    assert np.linalg.norm(c.object_point - centre) == pytest.approx(OBJECT_RADIUS, abs=1e-12)
    assert _dist_point_segment(c.object_point, a, b) < 1e-12
    np.testing.assert_allclose(c.pose.apply(c.tool_point), c.object_point, atol=1e-12)
    # no penetration anywhere on the (possibly non-convex) tool, and the push is along the cone axis
    disc = Disc(centre, OBJECT_RADIUS)
    assert penetration_depth(tool, c.pose, disc) < 1e-12
    assert abs(signed_distance(tool, c.pose, disc)) < 1e-9
    assert c.cone_offset == pytest.approx(0.0, abs=1e-12)
    push = c.pose.yaw + f.push_angle
    assert np.cos(push - direction) == pytest.approx(1.0)


@pytest.mark.parametrize("offset", [-0.5, -0.2, 0.0, 0.3, 0.5])
def test_given_yaw_accepts_directions_inside_the_cone_only(offset: float) -> None:
    tool = load_tool("slope")
    f = tool.face("inclined")  # theta_b = pi/6 ~ 0.5236
    yaw = 0.2
    direction = yaw + f.push_angle + offset
    c = contact_pose(tool, "inclined", [0.0, 0.15], direction, yaw=yaw)
    assert c.pose.yaw == yaw
    assert c.cone_offset == pytest.approx(offset)
    with pytest.raises(InputError, match="direction"):
        contact_pose(tool, "inclined", [0.0, 0.15], yaw + f.push_angle + 0.6, yaw=yaw)


def test_contact_range_is_enforced() -> None:
    tool = load_tool("t_shape")
    with pytest.raises(InputError, match="contact range"):
        contact_pose(tool, "stem_left", [0.0, 0.1], np.pi, s=0.9)
    # outside the declared range the stem contact would indeed penetrate the crossbar
    c = contact_pose(tool, "stem_left", [0.0, 0.1], np.pi, s=0.42)
    f = tool.face("stem_left")
    p = f.point(0.9)
    from tooltransfer.tools.pose import Pose2D

    x = c.object_point - c.pose.rotate(p)
    bad = Pose2D(x[0], x[1], c.pose.yaw)
    assert penetration_depth(tool, bad, Disc([0.0, 0.1], OBJECT_RADIUS)) > 1e-3


def test_polygonal_object_contact() -> None:
    square = PolygonObject(shapely.box(-0.015, -0.015, 0.015, 0.015))
    tool = load_tool("i_shape")
    centre = np.array([0.02, 0.12])
    c = contact_pose(tool, "top", centre, np.pi / 2 + 0.3, obj=square)
    placed = square.at(centre)
    tp = tool_polygon(tool, c.pose)
    assert tp.distance(placed) < 1e-12
    assert tp.intersection(placed).area < 1e-15
    assert placed.exterior.distance(shapely.Point(c.object_point)) < 1e-12


def test_object_models_validate() -> None:
    with pytest.raises(InputError, match="radius"):
        DiscObject(radius=0.0)
    with pytest.raises(InputError, match="convex"):
        PolygonObject(shapely.Polygon([(0, 0), (2, 0), (1, 0.5), (2, 2), (0, 2)]))


@pytest.mark.parametrize(
    ("tool_name", "face", "direction"),
    [
        ("finger", "left", np.pi),
        ("slope", "inclined", 0.75 * np.pi),
        ("finger", "upper", np.pi / 2),
    ],
)
def test_contact_on_platform_uses_the_omni_heading(
    tool_name: str, face: str, direction: float
) -> None:
    platform = OmniPlatform(a_t=LIBRARY[tool_name].a_t)
    centre = np.array([0.0, 0.17])
    res = contact_on_platform(LIBRARY[tool_name], face, centre, direction, platform)
    assert res.ik.reachable and res.contact is not None
    c = res.contact
    ik = inverse_kinematics(platform, c.pose.position)
    assert c.pose.yaw == pytest.approx(ik.heading, abs=1e-12)
    tool = LIBRARY[tool_name]
    a, b = _face_world(tool, c)
    assert _dist_point_segment(centre, a, b) == pytest.approx(OBJECT_RADIUS, abs=1e-9)
    assert res.in_cone == (abs(c.cone_offset) <= tool.face(face).theta_b)


def test_contact_on_platform_reports_unreachable() -> None:
    res = contact_on_platform(load_tool("finger"), "left", [0.0, 0.5], np.pi, OmniPlatform())
    assert not res.ik.reachable and res.contact is None and res.ik.reason == "radius"
