"""Exact convex decomposition of a simple polygon (Hertel-Mehlhorn on a constrained triangulation).

The outline is triangulated with shapely's constrained Delaunay triangulation (triangles use only
the outline's own vertices, so coordinates are exact), then adjacent pieces are merged greedily
while their union stays convex. Hertel and Mehlhorn (1983) show the result has at most four times
the minimum number of convex pieces. The decomposition is checked: pieces are convex, their areas
sum to the outline's area and their union equals the outline (relative tolerance ``rtol``).
"""

from __future__ import annotations

import shapely
from shapely.ops import unary_union

from tooltransfer.errors import InputError


def is_convex(poly: shapely.Polygon, rtol: float = 1e-12) -> bool:
    """True when ``poly`` equals its convex hull up to a relative area tolerance."""
    return bool(poly.convex_hull.area - poly.area <= rtol * max(poly.area, 1e-300))


def _merge(a: shapely.Polygon, b: shapely.Polygon, rtol: float) -> shapely.Polygon | None:
    shared = a.intersection(b)
    if shared.length <= 0.0:
        return None
    merged = unary_union([a, b])
    if not isinstance(merged, shapely.Polygon) or not is_convex(merged, rtol):
        return None
    return shapely.Polygon(shapely.simplify(merged, 0.0).exterior)


def convex_decomposition(
    outline: shapely.Polygon, rtol: float = 1e-9
) -> tuple[shapely.Polygon, ...]:
    """Convex pieces whose union is ``outline`` (a simple polygon without holes, area > 0).

    Returns:
        The pieces, each a convex shapely polygon in the outline's frame and units.

    Raises:
        InputError: the outline is not a valid polygon without holes, or the check fails.
    """
    if not isinstance(outline, shapely.Polygon) or not outline.is_valid or outline.area <= 0:
        raise InputError("outline", "a valid simple polygon with positive area", repr(outline)[:80])
    if len(outline.interiors) > 0:
        raise InputError("outline", "a polygon without holes", f"{len(outline.interiors)} hole(s)")
    if is_convex(outline, rtol):
        return (shapely.Polygon(shapely.simplify(outline, 0.0).exterior),)
    pieces = [
        shapely.Polygon(t.exterior) for t in shapely.constrained_delaunay_triangles(outline).geoms
    ]
    pieces = [p for p in pieces if p.area > rtol * outline.area]
    changed = True
    while changed:
        changed = False
        for i in range(len(pieces)):
            for j in range(i + 1, len(pieces)):
                m = _merge(pieces[i], pieces[j], rtol)
                if m is not None:
                    pieces[i] = m
                    del pieces[j]
                    changed = True
                    break
            if changed:
                break
    check_decomposition(outline, pieces, rtol)
    return tuple(pieces)


def check_decomposition(
    outline: shapely.Polygon, pieces: list[shapely.Polygon], rtol: float = 1e-9
) -> None:
    """Raise :class:`InputError` unless ``pieces`` are convex, disjoint and cover ``outline``."""
    area = outline.area
    for k, p in enumerate(pieces):
        if not is_convex(p, rtol):
            raise InputError(f"pieces[{k}]", "a convex polygon", "a non-convex piece")
    total = sum(p.area for p in pieces)
    if abs(total - area) > rtol * area:
        raise InputError("pieces", "disjoint pieces with the outline's area", f"{total} vs {area}")
    gap = outline.symmetric_difference(unary_union(pieces)).area
    if gap > rtol * area:
        raise InputError("pieces", "a union equal to the outline", f"symmetric difference {gap}")
