"""Placing a tool outline at many poses at once (the swept-clearance checks of switches, re-contacts and
pushes): the same polygons, bit for bit, as one shapely polygon per pose, and the same distances."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from tooltransfer.tools import load_tool
from tooltransfer.tools.library import library_names
from tooltransfer.tools.pose import placed_outlines, rotation


@pytest.mark.parametrize("name", library_names())
def test_outlines_placed_at_once_are_the_polygons_placed_one_by_one(name: str) -> None:
    ring = np.asarray(load_tool(name).outline.exterior.coords)
    rng = np.random.default_rng(7)
    for k in (1, 2, 37):
        xy, yaw = rng.normal(0.0, 0.15, (k, 2)), rng.uniform(-7.0, 7.0, k)
        one_by_one = [shapely.Polygon(ring @ rotation(a).T + p) for p, a in zip(xy, yaw, strict=True)]
        at_once = shapely.get_parts(placed_outlines(ring, xy, yaw))
        assert len(at_once) == k
        for a, b in zip(one_by_one, at_once, strict=True):
            assert np.array_equal(shapely.get_coordinates(a), shapely.get_coordinates(b))
        puck = shapely.Point(rng.normal(0.0, 0.15, 2)).buffer(0.0175, quad_segs=32)
        assert shapely.distance(placed_outlines(ring, xy, yaw), puck) == shapely.distance(
            shapely.GeometryCollection(one_by_one), puck)


def test_no_pose_places_nothing() -> None:
    placed = placed_outlines([[0.0, 0.0], [0.01, 0.0], [0.0, 0.01]], np.zeros((0, 2)), np.zeros(0))
    assert placed.is_empty and len(shapely.get_parts(placed)) == 0
