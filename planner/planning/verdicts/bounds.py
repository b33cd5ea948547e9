"""Over-approximations of what :class:`~tooltransfer.planner.planning.verdicts.rules.PushRules` allow: where a
face can push from (a polygon containing the exact region) and which directions the puck may move in
anywhere in a box (an arc containing every admissible direction there).

Outward rounding: arcs are drawn with circumscribed polygons (outer boundaries) and chords (inner
boundaries), obstacles with inscribed polygons, so every polygon here contains the exact set.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
import shapely

from tooltransfer.planner.planning.verdicts.rules import FaceRule, PushRules

#: Polygon pieces per full turn for arcs.
ARC_PIECES = 256


def polar_ranges(rule: FaceRule) -> tuple[float, float, float, float]:
    """``(r_lo, r_hi, psi_lo, psi_hi)``: the puck's distance [m] from the Omni's axis and its polar angle
    less the waist angle [rad] (``atan2(o, v)``) over the face's offset and reach ranges."""
    (o_lo, o_hi), (v_lo, v_hi) = rule.offset, rule.reach
    o_abs_min = 0.0 if o_lo <= 0.0 <= o_hi else min(abs(o_lo), abs(o_hi))
    r_lo = math.hypot(v_lo, o_abs_min)
    r_hi = math.hypot(v_hi, max(abs(o_lo), abs(o_hi)))
    psi = [math.atan2(o, v) for o in (o_lo, o_hi) for v in (v_lo, v_hi)]
    return r_lo, r_hi, min(psi), max(psi)


def offset_turns(rule: FaceRule, r_lo: float, r_hi: float) -> tuple[float, float]:
    """``(least, largest)`` of ``asin(o / r)`` [rad] over the face's offsets ``o`` and distances ``r`` in
    ``[r_lo, r_hi]`` [m] (monotone in both: the extremes are at the corners): how far the face's contact
    turns the tool's heading from the puck's polar angle (the heading is ``phi - asin(o / r) - pi/2``)."""
    asins = [math.asin(max(-1.0, min(1.0, o / r))) for o in rule.offset for r in (r_lo, r_hi)]
    return min(asins), max(asins)


def face_region(rules: PushRules, rule: FaceRule) -> shapely.Polygon:
    """A polygon [m] containing every puck position face ``rule`` can push from (an annular sector about
    the Omni's axis: circumscribed outer arc, inscribed inner chords)."""
    r_lo, r_hi, psi_lo, psi_hi = polar_ranges(rule)
    lo, hi = rules.waist[0] + psi_lo, rules.waist[1] + psi_hi
    n = max(2, math.ceil((hi - lo) / (2 * math.pi) * ARC_PIECES))
    ang = np.linspace(lo, hi, n + 1)
    # outer: tangent lines at the arc's n + 1 points meet outside the circle; a polygon through
    # points at radius r_hi / cos(step / 2) on the bisectors, with both ends pushed out radially
    step = (hi - lo) / n
    mid = np.concatenate([[lo], 0.5 * (ang[:-1] + ang[1:]), [hi]])
    rad = np.full(mid.size, r_hi / math.cos(step / 2))
    outer = np.column_stack([rad * np.cos(mid), rad * np.sin(mid)])
    inner = np.column_stack([r_lo * np.cos(ang[::-1]), r_lo * np.sin(ang[::-1])])
    b = np.asarray(rules.base)
    return shapely.Polygon(np.vstack([outer, inner]) + b)


def obstacle_zone(rules: PushRules) -> shapely.Geometry:
    """Inscribed polygons [m] of where the puck's centre may not be (each obstacle grown by the
    clearance); a subset of the exact zone, so the free space left is an over-approximation."""
    d = rules.clearance()
    parts = [shapely.Point(x, y).buffer(r + d, quad_segs=64) for x, y, r in rules.discs]
    parts += [p.buffer(d, quad_segs=64) for p in rules.polygons]
    return shapely.union_all(parts) if parts else shapely.Polygon()


def push_space(rules: PushRules) -> shapely.Geometry:
    """A polygon [m] containing every position the puck can be pushed from (the union of the faces'
    regions, obstacles' zones removed)."""
    regions = shapely.union_all([face_region(rules, f) for f in rules.faces]) if rules.faces else shapely.Polygon()
    return shapely.difference(regions, obstacle_zone(rules))


def _box_polar(base: np.ndarray, box: tuple[float, float, float, float]) -> tuple[float, float, float, float] | None:
    """``(d_lo, d_hi, phi_lo, phi_hi)``: distances [m] and polar angles [rad] of the box's points about
    ``base``; None when the box holds ``base`` (every angle)."""
    x0, y0, x1, y1 = box
    bx, by = float(base[0]), float(base[1])
    if x0 <= bx <= x1 and y0 <= by <= y1:
        return None
    cx, cy = min(max(bx, x0), x1), min(max(by, y0), y1)
    d_lo = math.hypot(cx - bx, cy - by)
    corners = [(x, y) for x in (x0, x1) for y in (y0, y1)]
    d_hi = max(math.hypot(x - bx, y - by) for x, y in corners)
    ref = math.atan2(0.5 * (y0 + y1) - by, 0.5 * (x0 + x1) - bx)
    rel = [math.remainder(math.atan2(y - by, x - bx) - ref, 2 * math.pi) for x, y in corners]
    return d_lo, d_hi, ref + min(rel), ref + max(rel)


def face_headings(rules: PushRules, rule: FaceRule, box: tuple[float, float, float, float]
                  ) -> tuple[float, float] | Literal[False] | None:
    """The tool's heading range ``(lo, hi)`` [rad] while face ``rule`` pushes the puck at a point of
    ``box`` ``(x0, y0, x1, y1)`` [m]; False when the face's region misses the box, None when the box
    holds the Omni's axis (any heading).

    The heading is ``phi - asin(o / r) - pi/2`` (polar angle ``phi`` and distance ``r`` about the
    Omni's axis, offset ``o``), bounded over the box and the face's offsets (monotone in ``o`` and
    ``r``: the extremes are at the corners)."""
    polar = _box_polar(np.asarray(rules.base), box)
    if polar is None:
        return None
    d_lo, d_hi, phi_lo, phi_hi = polar
    r_lo, r_hi, psi_lo, psi_hi = polar_ranges(rule)
    lo_r, hi_r = max(d_lo, r_lo), min(d_hi, r_hi)
    if lo_r > hi_r:
        return False
    f_lo, f_hi = rules.waist[0] + psi_lo, rules.waist[1] + psi_hi
    gap = abs(math.remainder(0.5 * (phi_lo + phi_hi) - 0.5 * (f_lo + f_hi), 2 * math.pi))
    if gap > 0.5 * (phi_hi - phi_lo) + 0.5 * (f_hi - f_lo) + 1e-12:
        return False
    least, largest = offset_turns(rule, lo_r, hi_r)
    return phi_lo - largest - math.pi / 2, phi_hi - least - math.pi / 2


def direction_arcs(rules: PushRules, box: tuple[float, float, float, float]) -> list[tuple[float, float]] | None:
    """Arcs ``(lo, hi)`` [rad] (world frame) holding every direction the puck may move in while at a
    point of ``box`` [m], one per face that may push there (empty: it cannot move); None: any."""
    arcs = []
    for f in rules.faces:
        hd = face_headings(rules, f, box)
        if hd is None:
            return None
        if hd is not False:
            arcs.append((hd[0] + f.cone[0], hd[1] + f.cone[1]))
    return arcs


def body_zone(rules: PushRules, rule: FaceRule, headings: tuple[float, float]) -> shapely.Geometry:
    """Puck positions [m] where the tool body overlaps an obstacle whatever the contact on face ``rule``
    and whatever the heading in ``headings`` [rad]: the obstacles (inscribed polygons) swept by the
    face's core turned to the middle heading and shrunk by how far the heading's spread can move it."""
    obstacles = [shapely.Point(x, y).buffer(r, quad_segs=16) for x, y, r in rules.discs] + list(rules.polygons)
    if not obstacles or not rule.core:
        return shapely.Polygon()
    mid, half = 0.5 * (headings[0] + headings[1]), 0.5 * (headings[1] - headings[0])
    c, s = math.cos(mid), math.sin(mid)
    rot = np.array([[c, -s], [s, c]])
    hulls = []
    for piece in rule.core:
        v = shapely.get_coordinates(piece)
        shrink = float(np.max(np.hypot(v[:, 0], v[:, 1]))) * half
        small = piece.buffer(-shrink, join_style="mitre") if shrink > 0 else piece
        if small.is_empty or shapely.get_type_id(small) != 3:
            continue
        w = shapely.get_coordinates(small) @ rot.T
        for o in obstacles:
            ov = shapely.get_coordinates(o)
            hulls.append(shapely.MultiPoint((ov[:, None, :] - w[None, :, :]).reshape(-1, 2)).convex_hull)
    return shapely.union_all(hulls) if hulls else shapely.Polygon()
