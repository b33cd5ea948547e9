"""The Omni's reachable table region: polygon, exact reach interval, and (G, h) inner rows."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import shapely

from tooltransfer.errors import InputError
from tooltransfer.tools.omni import (
    OmniPlatform,
    inner_row,
    inverse_kinematics,
    outer_rows,
    reach_sector,
    reachable_polygon,
    stack_rows,
    wedge_rows,
)
from tooltransfer.tools.omni.reach import reach_intervals

PLATFORMS = [
    OmniPlatform(),
    OmniPlatform(a_t=0.028),
    OmniPlatform(a_t=0.028, base_xy=(0.05, -0.02), base_yaw=1.2, table_height=0.015),
]


def _reachable(platform: OmniPlatform, pts: np.ndarray) -> np.ndarray:
    return np.array([inverse_kinematics(platform, p).reachable for p in pts])


def _cloud(poly: shapely.Polygon, n: int, seed: int, pad: float = 0.01) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x0, y0, x1, y1 = poly.bounds
    return rng.uniform([x0 - pad, y0 - pad], [x1 + pad, y1 + pad], size=(n, 2))


@pytest.mark.parametrize("platform", PLATFORMS)
def test_polygon_points_are_reachable_and_points_outside_are_not(platform: OmniPlatform) -> None:
    tol = 1e-4
    poly = reachable_polygon(platform, tol=tol)
    assert poly.is_valid
    pts = _cloud(poly, 4000, seed=3)
    inside = shapely.contains_xy(poly, pts[:, 0], pts[:, 1])
    dist = shapely.distance(poly, shapely.points(pts))
    assert inside.sum() > 1000
    assert _reachable(platform, pts[inside]).all()
    outside = pts[dist > 2 * tol]
    assert not _reachable(platform, outside).any()


@pytest.mark.parametrize("platform", PLATFORMS)
def test_polygon_boundary_reachable_and_just_outside_not(platform: OmniPlatform) -> None:
    tol = 1e-4
    poly = reachable_polygon(platform, tol=tol)
    ring = poly.exterior
    s = np.linspace(0.0, ring.length, 800, endpoint=False)
    on = np.array([ring.interpolate(v).coords[0] for v in s])
    assert _reachable(platform, on).all()
    # 1 mm outward along the edge normal (counter-clockwise ring: outward is to the right)
    ccw = shapely.geometry.polygon.orient(poly, 1.0).exterior
    out = []
    for v in s:
        a, b = np.array(ccw.interpolate(v).coords[0]), np.array(ccw.interpolate(v + 1e-6).coords[0])
        t = (b - a) / np.linalg.norm(b - a)
        p = a + 1e-3 * np.array([t[1], -t[0]])
        if poly.distance(shapely.Point(p)) > 5e-4:  # skip points that wrapped round a corner
            out.append(p)
    assert len(out) > 600
    assert not _reachable(platform, np.array(out)).any()


def test_reach_interval_is_exact() -> None:
    platform = PLATFORMS[0]
    sec = reach_sector(platform)
    for q1 in (-1.0, 0.0, 1.0):
        for u, ok in (
            (sec.u_range[0], True),
            (sec.u_range[1], True),
            (sec.u_range[0] - 1e-7, False),
            (sec.u_range[1] + 1e-7, False),
        ):
            assert inverse_kinematics(platform, sec.point(q1, u)).reachable is ok
    assert reach_intervals(platform) == [sec.u_range]


def test_region_contains_published_footprint_and_area() -> None:
    poly = reachable_polygon(OmniPlatform())
    box = shapely.box(-0.08, 0.13, 0.08, 0.20)  # 160 mm wide, 70 mm deep
    assert poly.contains(box)
    assert poly.area == pytest.approx(0.0390, abs=5e-4)
    fine = reachable_polygon(OmniPlatform(), tol=1e-6)
    assert fine.area >= poly.area
    assert poly.hausdorff_distance(fine) < 1e-4 + 1e-9


@pytest.mark.parametrize("platform", PLATFORMS)
def test_linear_rows_are_inner_approximations(platform: OmniPlatform) -> None:
    poly = reachable_polygon(platform, tol=1e-5)
    sec = reach_sector(platform)
    pts = _cloud(poly, 6000, seed=7, pad=0.05)
    wedge = wedge_rows(platform)
    outer = outer_rows(platform)
    mid = sec.point(0.5 * sum(sec.q1_range), 0.5 * sum(sec.u_range))
    for at in (mid, sec.point(sec.q1_range[0], sec.u_range[1])):
        rows = stack_rows(wedge, outer, inner_row(platform, at))
        ok = rows.satisfied(pts)
        assert ok.sum() > 200
        assert _reachable(platform, pts[ok]).all()
    # the tangent row touches the inner circle at the linearization direction
    row = inner_row(platform, mid)
    d = (mid - sec.centre) / np.linalg.norm(mid - sec.centre)
    touch = sec.centre + sec.r_in * d
    assert row.G @ touch == pytest.approx(row.h, abs=1e-15)
    # wedge + outer rows cover most of the exact region (inner approximation within tol)
    inner_pts = pts[shapely.contains_xy(poly, pts[:, 0], pts[:, 1])]
    covered = stack_rows(wedge, outer).satisfied(inner_pts, atol=1e-12)
    assert covered.mean() > 0.99


def test_wedge_rows_are_exact_on_the_sides() -> None:
    platform = PLATFORMS[2]
    sec = reach_sector(platform)
    wedge = wedge_rows(platform)
    for u in np.linspace(*sec.u_range, 5):
        lo = sec.point(sec.q1_range[0], u)
        hi = sec.point(sec.q1_range[1], u)
        assert (wedge.G @ lo - wedge.h)[0] == pytest.approx(0.0, abs=1e-15)
        assert (wedge.G @ hi - wedge.h)[1] == pytest.approx(0.0, abs=1e-15)


def test_invalid_reach_requests() -> None:
    with pytest.raises(InputError, match="at"):
        inner_row(OmniPlatform(), [0.0, 0.0])
    with pytest.raises(InputError, match="table_height"):
        reach_sector(OmniPlatform(table_height=-0.5))
    with pytest.raises(InputError, match="limits"):
        reach_sector(replace(OmniPlatform(), table_height=-0.02))  # reaches behind the shoulder
    with pytest.raises(InputError, match="tol"):
        reachable_polygon(OmniPlatform(), tol=0.0)
