"""A certificate by a quantity every admissible push increases: the puck's polar angle about the Omni's
axis less a function of its distance from it.

The rules (:mod:`.rules`) are the same at every polar angle about the Omni's axis but for the waist
range and the obstacles: with face ``f`` pushing the puck at distance ``r`` from the axis and polar
angle ``phi``, the tool's heading is ``phi - asin(o / r) - pi/2`` (``o``: the puck centre's offset from
the arm's plane, within the face's offsets), so the puck's direction of motion, measured from the
radial direction, lies in the face's cone turned by ``-asin(o / r) - pi/2``: an arc that depends on
``r`` only. Where, in every band ``[r_k, r_k+1]`` of distances, those arcs of every face fit in one
half-plane, the function

    V(p) = sigma * phi(p) - G(r(p)),    G' (r) = M_k / r on band k,

increases (does not decrease) along every push, for ``sigma`` = +1 or -1 and any slope ``M_k`` whose
direction ``atan(M_k)`` keeps the band's arcs on the increasing side (an interval of slopes per band,
:func:`slopes`). Between pushes the puck stands still. So every position a plan reaches has
``V >= V(start)``; if ``V`` is smaller than that everywhere on the target's goal disc, no plan
reaches the target. The slopes are chosen to make ``V(target)`` smallest: the largest allowed slope
between the start's and the target's distances when the target is farther out, the smallest when it
is nearer; elsewhere any allowed one (every band the puck can reach must allow one).

Over-approximation only, as for :mod:`.backward`: the obstacles, the waist range, the contact range's
rolling and the tool body are left out (each only removes plans), the arcs are bounded over the whole
band and every face's offsets (``asin(o / r)`` is monotone in ``o`` and ``r``: its extremes are at the
corners), and a face counts in every band that meets its distances. The polar angle is continuous on
the push space: it is an annular sector about the axis narrower than a turn (the waist range).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from tooltransfer.planner.planning.verdicts.bounds import offset_turns, polar_ranges
from tooltransfer.planner.planning.verdicts.rules import PushRules

#: Width [m] of the distance bands.
BAND = 1e-3
#: The largest slope magnitude used (any allowed slope is sound; this one keeps G finite).
MAX_SLOPE = 1e3
#: Room [rad] kept from the ends of a band's interval of slope angles (floating-point rounding).
ANGLE_ROOM = 1e-9
#: The least margin of ``V`` by which the goal disc must lie below the start (far above rounding).
V_GAP = 1e-6


@dataclass(frozen=True)
class Spiral:
    """A monotone quantity's parameters and what it shows.

    Attributes:
        sigma: +1 (the polar angle increases along pushes, less ``G``) or -1.
        edges: shape (K + 1,), the bands' distance edges [m] from the Omni's axis.
        slopes: shape (K,), ``M_k`` of each band.
        v_start: ``V`` at the start [rad].
        v_goal: the largest ``V`` on the target's goal disc [rad] (bounded).
    """

    sigma: int
    edges: np.ndarray
    slopes: np.ndarray
    v_start: float
    v_goal: float

    def to_dict(self) -> dict[str, object]:
        """JSON data (lengths in m, angles in rad)."""
        return {"sigma": self.sigma, "edges": self.edges.tolist(), "slopes": self.slopes.tolist(),
                "v_start": self.v_start, "v_goal": self.v_goal}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Spiral:
        """The invariant of :meth:`to_dict`'s data (its values are checked by :func:`check_spiral`)."""
        return cls(int(d["sigma"]), np.asarray(d["edges"], dtype=np.float64),
                   np.asarray(d["slopes"], dtype=np.float64), float(d["v_start"]), float(d["v_goal"]))


def relative_arcs(rules: PushRules, r_lo: float, r_hi: float) -> list[tuple[float, float]]:
    """Arcs ``(lo, hi)`` [rad] holding every direction of motion, measured from the radial direction,
    of a puck pushed at a distance in ``[r_lo, r_hi]`` [m] from the Omni's axis, one per face whose
    distances meet the band."""
    arcs = []
    for f in rules.faces:
        f_lo, f_hi, _, _ = polar_ranges(f)
        lo_r, hi_r = max(r_lo, f_lo), min(r_hi, f_hi)
        if lo_r > hi_r:
            continue
        least, largest = offset_turns(f, lo_r, hi_r)
        arcs.append((f.cone[0] - math.pi / 2 - largest, f.cone[1] - math.pi / 2 - least))
    return arcs


def _union(arcs: list[tuple[float, float]]) -> tuple[float, float] | None:
    """The smallest arc ``(lo, hi)`` [rad], ``hi - lo < 2 pi``, holding every arc of ``arcs`` (None: no
    arc; ``(0, 2 pi)`` where they need a whole turn)."""
    if not arcs:
        return None
    if any(hi - lo >= 2 * math.pi for lo, hi in arcs):
        return 0.0, 2 * math.pi
    best = None
    for lo0, _ in arcs:  # the union's start is one of the arcs' starts
        hi = lo0
        for lo, h in arcs:
            shift = (lo - lo0) % (2 * math.pi)
            hi = max(hi, lo0 + shift + (h - lo))
        if best is None or hi - lo0 < best[1] - best[0]:
            best = (lo0, hi)
    assert best is not None
    return best


def slopes(rules: PushRules, r_lo: float, r_hi: float, sigma: int) -> tuple[float, float] | None:
    """The interval ``(m_lo, m_hi)`` of slopes ``M`` for which ``sigma * phi - G`` (``G' = M / r``) does not
    decrease along any push at a distance in ``[r_lo, r_hi]`` [m]; None where none does. ``(-inf, inf)``
    where no face pushes there."""
    u = _union(relative_arcs(rules, r_lo, r_hi))
    if u is None:
        return -math.inf, math.inf
    t1, t2 = u
    if t2 - t1 >= math.pi:
        return None
    # a direction at angle t from the radial one changes sigma * phi - G at the rate
    # (sigma sin t - M cos t) / r; with b = atan(M) that is sqrt(1 + M^2) sin(t - b) / r for sigma = +1,
    # >= 0 for every t of [t1, t2] iff b is in [t2 - pi, t1], and -sqrt(1 + M^2) sin(t + b) / r for
    # sigma = -1, >= 0 iff b is in [pi - t1, 2 pi - t2] (mod 2 pi)
    lo, hi = (t2 - math.pi, t1) if sigma > 0 else (math.pi - t1, 2 * math.pi - t2)
    # the part of [lo, hi] (mod 2 pi) inside (-pi/2, pi/2): one interval (module docstring)
    best = None
    for k in (-2, -1, 0, 1, 2):
        a, b = max(lo + 2 * math.pi * k, -math.pi / 2), min(hi + 2 * math.pi * k, math.pi / 2)
        if a <= b:
            best = (a, b) if best is None or b - a > best[1] - best[0] else best
    if best is None:
        return None
    m_lo, m_hi = max(-MAX_SLOPE, math.tan(best[0] + ANGLE_ROOM)), min(MAX_SLOPE, math.tan(best[1] - ANGLE_ROOM))
    return (m_lo, m_hi) if m_lo <= m_hi else None  # (none within the slopes used)


def _mid(rules: PushRules) -> float:
    """The middle of the waist range [rad]: polar angles are taken within half a turn of it."""
    return 0.5 * (rules.waist[0] + rules.waist[1])


def _span(rules: PushRules, start: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """The least and largest distance [m] from the Omni's axis of any face's region, the start and the
    target: what the bands must cover."""
    r_s, r_t = _polar(rules, start)[0], _polar(rules, target)[0]
    ranges = [polar_ranges(f)[:2] for f in rules.faces]
    return min([r_s, r_t, *(lo for lo, _ in ranges)]), max([r_s, r_t, *(hi for _, hi in ranges)])


def _pick(iv: tuple[float, float], toward: float | None) -> float:
    """A slope of the interval ``iv`` (clipped to :data:`MAX_SLOPE`): its end in the direction of
    ``toward`` (+1: the largest, -1: the smallest), or with no direction the one nearest 0."""
    if toward is not None:
        m = iv[1] if toward > 0 else iv[0]
    else:
        m = min(max(0.0, iv[0]), iv[1])
    return min(MAX_SLOPE, max(-MAX_SLOPE, m))


def _one_branch(rules: PushRules) -> bool:
    """Whether every face's polar angles lie within half a turn of the waist range's middle (the branch
    :func:`_values` takes them on is then continuous on the push space)."""
    mid = _mid(rules)
    for f in rules.faces:
        _, _, psi_lo, psi_hi = polar_ranges(f)
        if rules.waist[0] + psi_lo <= mid - math.pi or rules.waist[1] + psi_hi >= mid + math.pi:
            return False
    return True


def _polar(rules: PushRules, p: np.ndarray) -> tuple[float, float]:
    d = np.asarray(p, dtype=np.float64) - np.asarray(rules.base)
    return float(np.hypot(d[0], d[1])), float(math.atan2(d[1], d[0]))


def _g(edges: np.ndarray, m: np.ndarray, r: float) -> float:
    """``G(r)`` [rad], ``G(edges[0]) = 0``."""
    k = int(np.clip(np.searchsorted(edges, r, side="right") - 1, 0, len(m) - 1))
    full = float(np.sum(m[:k] * np.log(edges[1:k + 1] / edges[:k])))
    return full + float(m[k] * math.log(r / edges[k]))


def _values(rules: PushRules, sp: Spiral, start: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """``(V(start), bound of V on the goal disc)`` [rad] of ``sp`` (the polar angles taken on one
    branch about the middle of the waist range, so that the push space's are continuous)."""
    mid = _mid(rules)
    r_s, phi_s = _polar(rules, start)
    r_t, phi_t = _polar(rules, target)
    phi_s = mid + math.remainder(phi_s - mid, 2 * math.pi)
    phi_t = mid + math.remainder(phi_t - mid, 2 * math.pi)
    v_s = sp.sigma * phi_s - _g(sp.edges, sp.slopes, r_s)
    tol = rules.goal_tol
    r_min = max(r_t - tol, 1e-9)
    near = (sp.edges[1:] >= r_min) & (sp.edges[:-1] <= r_t + tol)  # the bands the goal disc meets
    steep = float(np.max(np.abs(sp.slopes[near]))) if near.any() else float(np.max(np.abs(sp.slopes)))
    grad = math.sqrt(1.0 + steep ** 2) / r_min  # |grad V| on the disc
    v_t = sp.sigma * phi_t - _g(sp.edges, sp.slopes, r_t) + tol * grad
    return v_s, v_t


def invariant(rules: PushRules, start: np.ndarray, target: np.ndarray) -> Spiral | None:
    """The quantity of the module docstring with the slopes that make ``V(target)`` smallest, for the first
    ``sigma`` (+1, then -1) whose every band allows a slope; None where neither does. It proves the task
    infeasible only when ``v_goal < v_start``; otherwise its side of the start (:func:`start_side`) still
    holds every position a plan reaches."""
    if not rules.faces or not _one_branch(rules):
        return None
    lo, hi = _span(rules, start, target)
    lo, hi = lo - BAND, hi + BAND
    if lo <= 0.0:
        return None
    n = max(1, math.ceil((hi - lo) / BAND))
    edges = lo + (hi - lo) * np.arange(n + 1) / n  # bands of at most BAND, increasing, ending at hi
    r_s, r_t = _polar(rules, start)[0], _polar(rules, target)[0]
    toward = 1.0 if r_t > r_s else -1.0  # between the two distances, the slope that lowers V(target) most
    for sigma in (1, -1):
        m = []
        for a, b in itertools.pairwise(edges):
            iv = slopes(rules, float(a), float(b), sigma)
            if iv is None:
                break
            m.append(_pick(iv, toward if min(r_s, r_t) <= b and a <= max(r_s, r_t) else None))
        else:
            sp = Spiral(sigma, edges, np.asarray(m), 0.0, 0.0)
            v_s, v_t = _values(rules, sp, start, target)
            return Spiral(sigma, edges, sp.slopes, v_s, v_t)
    return None


def check_spiral(rules: PushRules, sp: Spiral, start: np.ndarray, target: np.ndarray, *,
                 separating: bool = True) -> list[str]:
    """What is wrong with ``sp`` (empty: it holds): every band's slope recomputed against ``rules``, the
    bands covering every distance a face pushes from, and (``separating``) the start above the goal disc."""
    problems = []
    if not _one_branch(rules):
        problems.append("the push space's polar angles span more than a turn")
    if sp.sigma not in (1, -1):
        problems.append("sigma is neither +1 nor -1")
    e = np.asarray(sp.edges)
    if len(e) != len(sp.slopes) + 1 or np.any(np.diff(e) <= 0.0) or e[0] <= 0.0:
        return [*problems, "the bands are not increasing distances"]
    lo, hi = _span(rules, start, target)
    if e[0] > lo or e[-1] < hi:
        problems.append("the bands do not cover the push space, the start and the target")
    for k, (a, b) in enumerate(itertools.pairwise(e)):
        iv = slopes(rules, float(a), float(b), sp.sigma)
        if iv is None or not iv[0] <= sp.slopes[k] <= iv[1]:
            problems.append(f"band {k} ({a * 1e3:.1f}-{b * 1e3:.1f} mm): slope {sp.slopes[k]:.4g} not allowed")
            break
    v_s, v_t = _values(rules, sp, start, target)
    if separating and not v_t < v_s - V_GAP:
        problems.append("the goal disc is not below the start")
    return problems


#: Outward growth [m] of :func:`start_side`'s polygon: above the chords' distance from the curves they
#: stand for (arcs of at most 1 degree and band-edge chords of a spiral: under 2e-5 m within 0.3 m).
SIDE_GROWTH = 1e-4


def start_side(rules: PushRules, sp: Spiral, start: np.ndarray, *, step: float = math.radians(1.0)
               ) -> shapely.Geometry:
    """A polygon [m] holding every position of the push space where ``V >= V(start)`` (``V(start)``
    computed here from ``start`` (2,) [m], not taken from ``sp``): every position a plan from the start
    reaches lies in it. The curve ``V = V(start)`` is drawn through each band edge and at most ``step``
    [rad] of polar angle apart, the polygon grown by :data:`SIDE_GROWTH`."""
    mid = _mid(rules)
    v_s, _ = _values(rules, sp, start, start)
    e = np.asarray(sp.edges)
    pts = [e[0]]
    for a, b, m in zip(e[:-1], e[1:], sp.slopes, strict=True):  # on band k the curve turns by M ln(b / a)
        n = max(1, math.ceil(abs(m) * math.log(b / a) / step))
        pts += list(a * (b / a) ** (np.arange(1, n + 1) / n))
    r = np.asarray(pts)
    g = np.array([_g(e, sp.slopes, float(x)) for x in r])
    low, high = mid - math.pi + 1e-6, mid + math.pi - 1e-6
    bound = np.clip(sp.sigma * (v_s + g), low, high)  # the polar angle where V = V(start)
    far = high if sp.sigma > 0 else low

    def arc(radius: float, a: float, b: float) -> np.ndarray:
        k = max(2, math.ceil(abs(b - a) / step) + 1)
        t = np.linspace(a, b, k)
        return np.column_stack([radius * np.cos(t), radius * np.sin(t)])

    ring = np.vstack([np.column_stack([r * np.cos(bound), r * np.sin(bound)]), arc(float(r[-1]), bound[-1], far),
                      np.column_stack([r[::-1] * math.cos(far), r[::-1] * math.sin(far)]),
                      arc(float(r[0]), far, bound[0])]) + np.asarray(rules.base)
    return _grown(shapely.make_valid(shapely.Polygon(ring)))


def _grown(g: shapely.Geometry) -> shapely.Geometry:
    """``g`` grown by :data:`SIDE_GROWTH`, its lines merged first: where the polar angle is clipped the ring
    runs back along itself, and ``make_valid`` leaves that as thousands of short collinear lines (17,682 on
    ``problems/hard/only_face_pushes_away.yaml``), which GEOS buffers in some 45 s as they are and in
    milliseconds as the one line they form (the same set: a buffer of a union is the union of the buffers)."""
    parts = shapely.get_parts(g)
    dims = shapely.get_dimensions(parts)
    pieces = list(parts[dims != 1])
    if (dims == 1).any():
        pieces.append(shapely.line_merge(shapely.union_all(parts[dims == 1])))
    return shapely.union_all(shapely.buffer(pieces, SIDE_GROWTH))
