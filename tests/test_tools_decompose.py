"""Convex decomposition: pieces are convex, disjoint, and their union is the outline."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.ops import unary_union

from tooltransfer.errors import InputError
from tooltransfer.tools import convex_decomposition, load_library
from tooltransfer.tools.decompose import check_decomposition, is_convex


def _assert_exact(outline: shapely.Polygon, pieces: tuple[shapely.Polygon, ...]) -> None:
    assert all(is_convex(p) for p in pieces)
    assert sum(p.area for p in pieces) == pytest.approx(outline.area, rel=1e-12)
    assert outline.symmetric_difference(unary_union(pieces)).area <= 1e-12 * outline.area
    for i, a in enumerate(pieces):
        for b in pieces[i + 1 :]:
            assert a.intersection(b).area <= 1e-12 * outline.area


@pytest.mark.parametrize(("name", "tool"), sorted(load_library().items()))
def test_library_outlines(name: str, tool) -> None:
    pieces = tool.convex_pieces
    _assert_exact(tool.outline, pieces)
    expected = {"t_shape": 2, "l_shape": 2, "spatula": 2, "cross_head": 3, "rake": 4}.get(name, 1)
    assert len(pieces) == expected


@settings(derandomize=True, max_examples=60, deadline=None)
@given(
    n=st.integers(3, 12),
    radii=st.lists(st.floats(0.2, 1.0), min_size=24, max_size=24),
    phase=st.floats(0.0, 1.0),
)
def test_random_star_polygons(n: int, radii: list[float], phase: float) -> None:
    k = 2 * n
    ang = phase + np.linspace(0.0, 2 * np.pi, k, endpoint=False)
    r = np.array(radii[:k])
    outline = shapely.Polygon(np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1))
    pieces = convex_decomposition(outline)
    _assert_exact(outline, pieces)
    # Hertel-Mehlhorn bound: at most the number of triangles, at most 4x optimum (>= 1)
    assert len(pieces) <= k - 2


def test_comb_polygon_needs_one_piece_per_tooth() -> None:
    teeth = 5
    pts = [(0.0, 0.0), (2.0 * teeth - 1.0, 0.0)]
    for i in reversed(range(teeth)):
        x = 2.0 * i
        pts += [(x + 1.0, 1.0), (x + 1.0, 3.0), (x, 3.0)] + ([(x, 1.0)] if i else [])
    comb = shapely.Polygon(pts)  # a 1-high spine with `teeth` 1 x 2 teeth on top
    assert comb.is_valid
    pieces = convex_decomposition(comb)
    _assert_exact(comb, pieces)
    assert teeth <= len(pieces) <= 2 * teeth


def test_check_detects_a_missing_piece() -> None:
    square = shapely.box(0, 0, 1, 1)
    with pytest.raises(InputError, match="area"):
        check_decomposition(square, [shapely.box(0, 0, 0.5, 1)])
    with pytest.raises(InputError, match="convex"):
        check_decomposition(square, [shapely.Polygon([(0, 0), (1, 0), (0.5, 0.5), (1, 1), (0, 1)])])


def test_rejects_holes_and_invalid() -> None:
    with pytest.raises(InputError, match="holes"):
        convex_decomposition(shapely.box(0, 0, 2, 2).difference(shapely.box(0.5, 0.5, 1, 1)))
    with pytest.raises(InputError, match="valid"):
        convex_decomposition(shapely.Polygon([(0, 0), (1, 1), (1, 0), (0, 1)]))
