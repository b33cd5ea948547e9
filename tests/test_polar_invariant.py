"""The ``polar_invariant`` certificate: the slopes it allows keep every admissible direction on the
increasing side (checked by sampling the cones, not with the module's arcs), a generated task it
certifies is checked again, and this file's own kinematics (the lattice search of
``test_verdicts``) finds no push that decreases its quantity and no way to the target."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely
from test_verdicts import _cone, _holds, _rules_of, generated, lattice_search

from tooltransfer.planner.planning.verdicts.certificate import certify, check_certificate
from tooltransfer.planner.planning.verdicts.rules import FaceRule, PushRules
from tooltransfer.planner.planning.verdicts.spiral import Spiral, slopes

ROOT = Path(__file__).resolve().parents[1]


def _rules(faces: list[FaceRule]) -> PushRules:
    return PushRules(tuple(faces), (0.0, 0.0), (0.5, 2.6), 0.0175, 0.002, (), (), math.atan(0.8))


def _rates(face: FaceRule, r_lo: float, r_hi: float, sigma: int, m: float, n: int = 9) -> np.ndarray:
    """``sigma sin t - m cos t`` over directions ``t`` (from the radial one) of ``face`` at distances in
    ``[r_lo, r_hi]``, sampled: cone angle, offset and distance on grids that hold their ends."""
    c = np.linspace(*face.cone, n)[:, None, None]
    o = np.linspace(*face.offset, n)[None, :, None]
    r = np.linspace(r_lo, r_hi, n)[None, None, :]
    t = c - math.pi / 2 - np.arcsin(o / r)
    return sigma * np.sin(t) - m * np.cos(t)


@pytest.mark.parametrize("seed", range(6))
def test_the_slopes_allowed_keep_every_direction_on_the_increasing_side(seed: int) -> None:
    rng = np.random.default_rng(seed)
    faces = []
    for k in range(int(rng.integers(1, 4))):
        mid, half = rng.uniform(-math.pi, math.pi), rng.uniform(0.05, 0.5)
        o = np.sort(rng.uniform(-0.04, 0.04, 2))
        faces.append(FaceRule(f"f{k}", (mid - half, mid + half), (float(o[0]), float(o[1])), (0.06, 0.25)))
    rules = _rules(faces)
    found = 0
    for r_lo in (0.07, 0.12, 0.2):
        r_hi = r_lo + 0.001
        for sigma in (1, -1):
            iv = slopes(rules, r_lo, r_hi, sigma)
            if iv is None:
                continue
            found += 1
            assert iv[0] <= iv[1]
            for m in (iv[0], 0.5 * (iv[0] + iv[1]), iv[1]):
                assert all((_rates(f, r_lo, r_hi, sigma, m) >= -1e-9).all() for f in faces), (sigma, m, iv)
            for m, step in ((iv[0], -1), (iv[1], 1)):  # just beyond an end, some direction decreases it
                beyond = math.tan(math.atan(m) + step * 1e-3)
                if abs(m) < 1e2:
                    assert any((_rates(f, r_lo, r_hi, sigma, beyond) < 0).any() for f in faces), (sigma, m)
    if len(faces) == 1:
        assert found  # one narrow cone always fits in a half-plane


def _generated(task_id: str):
    return generated("verdicts_200.yaml", task_id)


def _value(inv: dict, base: np.ndarray, mid: float, p: np.ndarray) -> tuple[float, float, float]:
    """``(V, dV/dx, dV/dy)`` of the stored invariant at ``p`` [m], computed here: the polar angle on the
    branch about ``mid``, ``G`` integrated band by band."""
    e, m = np.asarray(inv["edges"]), np.asarray(inv["slopes"])
    d = p - base
    r = float(np.hypot(*d))
    phi = mid + math.remainder(math.atan2(d[1], d[0]) - mid, 2 * math.pi)
    k = min(max(int(np.searchsorted(e, r, side="right")) - 1, 0), len(m) - 1)
    g = sum(m[j] * math.log(e[j + 1] / e[j]) for j in range(k)) + m[k] * math.log(r / e[k])
    grad_phi = np.array([-d[1], d[0]]) / r**2
    grad_r = d / r
    grad = inv["sigma"] * grad_phi - m[k] / r * grad_r
    return inv["sigma"] * phi - g, float(grad[0]), float(grad[1])


def test_a_generated_task_certified_by_the_polar_invariant_and_checked_by_this_files_kinematics(tmp_path) -> None:
    """``verd200-00021`` (slope tool, no obstacle, the target 50 mm farther out from the Omni at the same
    polar angle): every face's cone leans the puck round the axis as it moves out, so the target is
    out of reach. The guided search closes its space; the backward set on 2.5 mm cells reaches the start
    (each block turns the cones by its polar width); the invariant proves it in milliseconds."""
    from tooltransfer.planner.apps.plots.certificate import certificate_figure

    task = _generated("verd200-00021")
    setting, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    cert, why = certify(rules, start, target)
    assert cert is not None and cert.kind == "polar_invariant", why
    assert check_certificate(cert, rules) == []
    inv = cert.to_dict()["invariant"]
    base, mid = np.asarray(rules.base), 0.5 * (rules.waist[0] + rules.waist[1])
    assert _value(inv, base, mid, target)[0] + 1e-4 * 2 / 0.1 < _value(inv, base, mid, start)[0]
    # every push this file's kinematics finds, anywhere the tool holds the puck, keeps V from decreasing
    mu_half = math.atan(setting.mechanics.mu)
    checked = 0
    for x in np.arange(-0.25, 0.25, 0.006):
        for y in np.arange(0.0, 0.26, 0.006):
            p = np.array([x, y])
            _, gx, gy = _value(inv, base, mid, p)
            for face in setting.tool.faces:
                lo, hi = _cone(face, mu_half)
                if hi < lo:
                    continue
                for yaw in _holds(setting.tool, face, setting.platform, p, setting.radius, []):
                    for ang in np.linspace(lo, hi, 7):
                        w = yaw + face.normal_angle + ang
                        assert gx * math.cos(w) + gy * math.sin(w) >= -1e-9, (p, face.name, w)
                        checked += 1
    assert checked > 1000
    closest = lattice_search(setting, start, target)
    assert closest > 0.003, f"the lattice search came {closest * 1e3:.2f} mm from the target of a certified task"
    assert shapely.distance(cert.region, shapely.Point(target)) > 0.005  # drawn: the start's side of V
    png = certificate_figure({"certificate": cert.to_dict()}, [], tmp_path / "cert.png")
    assert png.stat().st_size > 10_000


def test_a_tampered_polar_invariant_fails_its_check() -> None:
    task = _generated("verd200-00021")
    _, rules = _rules_of(task)
    cert, _ = certify(rules, np.array(task.start), np.array(task.target))
    assert cert is not None and cert.kind == "polar_invariant"
    inv = cert.extra["invariant"]
    steep = dict(inv, slopes=[s + 50.0 for s in inv["slopes"]])
    cert.extra = {"invariant": steep}
    assert any("not allowed" in p for p in check_certificate(cert, rules))
    flat = dict(inv, slopes=[0.0] * len(inv["slopes"]))  # allowed in every band, but proves nothing
    cert.extra = {"invariant": flat}
    problems = check_certificate(cert, rules)
    assert problems == ["the goal disc is not below the start"] or any("not allowed" in p for p in problems)
    short = dict(inv, edges=inv["edges"][5:], slopes=inv["slopes"][5:])
    cert.extra = {"invariant": short}
    assert any("do not cover" in p for p in check_certificate(cert, rules))
    assert Spiral.from_dict(inv).sigma == inv["sigma"]


@pytest.mark.parametrize("task_id", ["verd200-00021", "verd200-00025"])
def test_the_start_side_polygon_holds_every_position_where_the_quantity_is_at_least_the_starts(task_id: str) -> None:
    """The restricted backward set is sound only if the polygon of the start's side holds every position
    of the push space with ``V >= V(start)``: checked on 20,000 random positions with ``V`` computed
    here (``verd200-00025``: the invariant does not separate start and target there; the backward set is
    grown on the start's side)."""
    from tooltransfer.planner.planning.verdicts.bounds import push_space
    from tooltransfer.planner.planning.verdicts.spiral import invariant, start_side

    task = _generated(task_id)
    _, rules = _rules_of(task)
    start, target = np.array(task.start), np.array(task.target)
    sp = invariant(rules, start, target)
    assert sp is not None
    side, space = start_side(rules, sp, start), push_space(rules)
    inv = sp.to_dict()
    base, mid = np.asarray(rules.base), 0.5 * (rules.waist[0] + rules.waist[1])
    v_start = _value(inv, base, mid, start)[0]
    x0, y0, x1, y1 = space.bounds
    rng = np.random.default_rng(7)
    pts = np.column_stack([rng.uniform(x0, x1, 20000), rng.uniform(y0, y1, 20000)])
    inside = shapely.contains_xy(space, pts[:, 0], pts[:, 1])
    above = np.array([_value(inv, base, mid, p)[0] >= v_start for p in pts])
    held = shapely.contains_xy(side, pts[:, 0], pts[:, 1])
    assert (inside & above).sum() > 1000 and (inside & ~above).sum() > 1000  # both sides sampled
    assert not (inside & above & ~held).any()
    # and it reaches beyond the curve V = V(start) by no more than its growth (0.1 mm) and the chords
    steep = float(np.max(np.abs(inv["slopes"])))
    r_min = min(float(np.hypot(*(q - base))) for q in pts[inside])
    below = [v_start - _value(inv, base, mid, q)[0] for q in pts[inside & ~above & held]]
    assert max(below, default=0.0) <= 2e-4 * math.sqrt(1 + steep**2) / r_min
