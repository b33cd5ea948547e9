"""The ``forward_backward`` certificate (verdicts/polar_sets.py): its map, a task it certifies replayed against
the test suite's own lattice search, and its check refusing sets that are not closed.

``verd200-00147`` (trapezoid, one disc): the only way past the obstacle runs inside it, along ``left``'s
highest direction, whose edge from the start runs 0.24 mm into the obstacle's margin (integrated in 10 um
steps, benchmarks/README.md); the square-cell sets of the other kinds let it through, the log-polar ones do not.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from test_verdicts import ROOT, _rules_of, generated, lattice_search

from tooltransfer.planner.planning.verdicts.certificate import certify_both_ways, check_certificate
from tooltransfer.planner.planning.verdicts.polar_sets import (
    DENSE,
    FORWARD_FIRST,
    IMAGE_ROOM,
    LogPolar,
    PolarWorld,
    stored_sets,
    world_region,
)
from tooltransfer.problems.task import load_task


def test_the_map_is_conformal_and_turns_a_direction_by_the_polar_angle() -> None:
    """A short world step in direction ``w`` at a point of polar angle ``phi`` maps to a step in direction
    ``w - phi`` (what the certificate's cones rest on), and the map goes back to where it came from."""
    lp = LogPolar((0.01, -0.02), 0.15, 0.7)
    rng = np.random.default_rng(3)
    for _ in range(20):
        r, phi, w = rng.uniform(0.08, 0.25), rng.uniform(0.0, 1.4), rng.uniform(-math.pi, math.pi)
        p = np.asarray(lp.base) + r * np.array([math.cos(phi), math.sin(phi)])
        step = 1e-7 * np.array([math.cos(w), math.sin(w)])
        d = lp.forward(p + step)[0] - lp.forward(p)[0]
        assert abs(math.remainder(math.atan2(d[1], d[0]) - (w - phi), 2 * math.pi)) < 1e-6
        assert math.hypot(*d) == pytest.approx(1e-7 * lp.r0 / r, rel=1e-5)
        assert np.allclose(lp.inverse(lp.forward(p)), p, atol=1e-12)


def test_a_mapped_edge_stays_within_the_room_kept_from_the_curve_it_stands_for() -> None:
    """A world edge of :data:`DENSE` maps to a chord of its true image (a curve): the zones are shrunk and the
    goal grown by :data:`IMAGE_ROOM` so that the chords' polygons stay inside (outside) the true images; the
    chord's distance from the curve, sampled over distances of 0.03-0.35 m and ``r0`` of 0.1-0.3 m, is below it."""
    rng = np.random.default_rng(0)
    worst = 0.0
    for r0 in (0.1, 0.2, 0.3):
        lp = LogPolar((0.0, 0.0), r0, 0.5)
        for _ in range(3000):
            r, a, w = rng.uniform(0.03, 0.35), rng.uniform(-1.0, 2.0), rng.uniform(-math.pi, math.pi)
            p = r * np.array([math.cos(a), math.sin(a)])
            m = lp.forward(p + DENSE * np.linspace(0.0, 1.0, 21)[:, None] * np.array([math.cos(w), math.sin(w)]))
            d = m[-1] - m[0]
            worst = max(worst, float(np.abs((m - m[0]) @ np.array([-d[1], d[0]]) / math.hypot(*d)).max()))
    assert worst < 0.5 * IMAGE_ROOM, worst


@pytest.fixture(scope="module")
def certified():
    """``verd200-00147``'s setting, rules, start, target and certificate."""
    task = generated("verdicts_200.yaml", "verd200-00147")
    setting, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    cert, why = certify_both_ways(rules, start, target)
    assert cert is not None and cert.kind == "forward_backward", why
    assert cert.extra["blocks_processed"] > FORWARD_FIRST  # F without B did not close: B was built
    return setting, rules, start, target, cert


def test_a_task_certified_both_ways_is_checked_again_and_the_lattice_search_stays_in_its_sets(certified) -> None:
    setting, rules, start, target, cert = certified
    assert check_certificate(cert, rules) == []
    visited: list = []
    closest = lattice_search(setting, start, target, ends_held=True, visited=visited)
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"
    # B is a thin strip past the inside of the obstacle: few of the search's positions lie in it, more with 1 mm
    # steps (9 of some 8300 here), and those must lie in F
    visited = []
    lattice_search(setting, start, target, step=0.001, cell=0.0005, budget=8000, directions=9, ends_held=True,
                   visited=visited)
    lp, back, ahead = stored_sets(cert.rules["base"], cert.extra)
    at = shapely.points(lp.forward(np.asarray(visited)))
    inside = shapely.covers(back, at)
    assert inside.sum() > 3  # the start and some positions pushed from it
    # each is reachable from the start, so F holds it (a step along a cone's edge may cut F's boundary by
    # hundredths of a millimetre)
    assert float(shapely.distance(ahead, at[inside]).max()) < 5e-4
    # drawn in the world, the set is where the plane's set is
    assert shapely.distance(world_region(lp, ahead), shapely.Point(start)) < 1e-4


def test_a_forward_backward_certificate_whose_sets_are_cut_fails_its_check(certified) -> None:
    _, rules, start, _, cert = certified
    lp, back, ahead = stored_sets(cert.rules["base"], cert.extra)
    s = lp.forward(start)[0]

    def with_(**changes):
        cert.extra, old = {**cert.extra, **changes}, cert.extra
        try:
            return check_certificate(cert, rules)
        finally:
            cert.extra = old

    # F without a band 4 mm beyond the start: what the start's pushes reach is no longer all in it
    band = shapely.difference(shapely.Point(s).buffer(0.006), shapely.Point(s).buffer(0.004))
    cut = with_(ahead_wkt=shapely.to_wkt(shapely.difference(ahead, band), rounding_precision=-1))
    assert any("F: block" in p and "not closed" in p for p in cut), cut
    # F without the start's disc
    cut = with_(ahead_wkt=shapely.to_wkt(shapely.difference(ahead, shapely.Point(s).buffer(1e-3)),
                                         rounding_precision=-1))
    assert "F does not hold the start's disc" in cut
    # B without a piece about a point of F (its closure breaks there, or F's within it)
    hole = shapely.intersection(back, shapely.point_on_surface(ahead).buffer(0.002))
    assert hole.area > 0.0
    cut = with_(back_wkt=shapely.to_wkt(shapely.difference(back, hole), rounding_precision=-1))
    assert any(p.startswith("B: block") or "F: block" in p for p in cut), cut
    # another map
    cut = with_(map={"r0": cert.extra["map"]["r0"] * 1.01, "phi0": cert.extra["map"]["phi0"]})
    assert cut == ["the map is not the one about the Omni's axis and the target"]
    assert with_(back_wkt="not wkt")[0].startswith("the stored sets cannot be read")


def test_f_closed_without_b_is_a_certificate_with_b_the_whole_push_space() -> None:
    """``small-00006`` (slope, two obstacles): ``F`` grown first without ``B`` closes away from the target, so
    it is the certificate with ``B`` the whole push space (trivially closed backward); the check replays it, the
    lattice search stays out of reach of the target and in ``F``, and ``F`` cut is refused."""
    task = generated("small.yaml", "small-00006")
    setting, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    cert, why = certify_both_ways(rules, start, target)
    assert cert is not None, why
    assert cert.extra["blocks_processed"] <= FORWARD_FIRST  # B was not built
    lp, back, ahead = stored_sets(cert.rules["base"], cert.extra)
    world = PolarWorld.of(rules, lp)
    assert shapely.covers(shapely.buffer(back, 1e-9), world.space)
    assert check_certificate(cert, rules) == []
    visited: list = []
    closest = lattice_search(setting, start, target, ends_held=True, visited=visited)
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"
    assert float(shapely.distance(ahead, shapely.points(lp.forward(np.asarray(visited)))).max()) < 5e-4
    s = lp.forward(start)[0]
    band = shapely.difference(shapely.Point(s).buffer(0.006), shapely.Point(s).buffer(0.004))
    cert.extra = {**cert.extra, "ahead_wkt": shapely.to_wkt(shapely.difference(ahead, band), rounding_precision=-1)}
    assert any("F: block" in p and "not closed" in p for p in check_certificate(cert, rules))


def test_f_at_the_target_without_b_leaves_b_unbuilt() -> None:
    """The paper's transfer (a solved task): ``F`` without ``B`` comes to the target within a few hundred updates,
    so ``B`` (some 20 s on its wide push space) is not built and nothing is certified."""
    task = load_task(ROOT / "problems" / "paper" / "transfer_tool2.yaml")
    _, rules = _rules_of(task)
    cert, why = certify_both_ways(rules, np.array(task.start), np.array(task.target))
    assert cert is None
    assert "the set F (without B): it came within the gap of the target's goal disc" in why
    assert int(why.rsplit("after ", 1)[1].split()[0]) < FORWARD_FIRST
