"""Property tests for the OE mappings (tooltransfer.planner.learning.oe_mappings, oe_outer_mappings,
oe_point_mappings, oe_map_parameters): eqs. (6) and (7) of the paper, their exact inverses, clipping.

Accuracy statements tested here (see the module docstring for the derivations):

- The forward maps and the inverses are accurate to 1e-15 relative against 60-digit references
  (decimal), i.e. to a few ulps of the exact value for the given double input.
- Round trips universal -> condensed -> universal hold to 1e-12 relative wherever the round trip's
  condition number ``kappa`` is at most 1e3 and the condensed value is a normal double. Elsewhere the
  relative error of the round trip is not a property of the code (the condensed double does not hold
  enough digits: ``kappa = (e^u - 1)/u`` near a saturating bound, ``r_g / (r_p (1 - k e^{-u}))`` near
  ``r_p = 0`` for the outer map), so there we check backward stability instead: ``f(f^-1(y)) = y`` to
  8 ulps. Subnormal images carry an absolute error of one subnormal spacing (4.9e-324) divided by k.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import numpy as np
import pytest
from hypothesis import event, example, given, settings
from hypothesis import strategies as st

from tooltransfer.errors import InputError
from tooltransfer.planner.learning import oe_map_parameters as prm
from tooltransfer.planner.learning import oe_mappings as mp
from tooltransfer.planner.learning import oe_outer_mappings as om
from tooltransfer.planner.learning import oe_point_mappings as pm

pytestmark = pytest.mark.filterwarnings("error")  # any warning (overflow, invalid, divide) fails a test

EPS = float(np.finfo(np.float64).eps)
TINY = float(np.finfo(np.float64).tiny)
FMAX = float(np.finfo(np.float64).max)
RTOL = 1e-12  # round trips, relative
ACC = 1e-15  # accuracy against the 60-digit reference, relative
KAPPA_MAX = 1e3

SETTINGS = settings(derandomize=True, max_examples=300, deadline=None)
SETTINGS_DECIMAL = settings(derandomize=True, max_examples=120, deadline=None)

# every valid parameter: for the safety properties (bounds, monotonicity, no warnings, backward stability)
ks = st.floats(TINY, 1.0, exclude_max=True)
theta_bs = st.floats(TINY, math.pi / 2)
r_bs = st.floats(TINY, prm.MAX_RADIUS)
# physically meaningful parameters: for the accuracy claims (a cone of 1 urad, a nanometre to a kilometre; any
# k in [1e-6, 1)); near-underflow bounds leave intermediate values subnormal, with fewer significant bits
ks_acc = st.floats(1e-6, 1.0, exclude_max=True)
theta_bs_acc = st.floats(1e-6, math.pi / 2)
r_bs_acc = st.floats(1e-9, 1e3)
deltas = st.floats(0.0, prm.MAX_RADIUS)
special = [0.0, 5e-324, 1e-310, 1e-300, 1e-12, 1.0, 37.0, 1e12, 1e300]
any_reals = st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from(special + [-x for x in special] + [FMAX])
radii = st.floats(0.0, prm.MAX_RADIUS) | st.sampled_from(special)


# --------------------------------------------------------------------------------------------------
# 60-digit references


def _d(x: float) -> Decimal:
    return Decimal(x)


def ref_saturate(x: float, b: float, k: float) -> Decimal:
    """b (1 - exp(-k x / b)) exactly to 60 digits, for x >= 0."""
    with localcontext() as ctx:
        ctx.prec = 60
        z = _d(k) * _d(x) / _d(b)
        if z < Decimal("1e-25"):
            return _d(b) * (z - z * z / 2)
        if z > 1000:
            return _d(b)
        return _d(b) * (1 - (-z).exp())


def ref_saturate_inverse(y: float, b: float, k: float) -> Decimal:
    with localcontext() as ctx:
        ctx.prec = 60
        t = _d(y) / _d(b)
        if t < Decimal("1e-25"):
            return _d(b) / _d(k) * (t + t * t / 2)
        return -(_d(b) / _d(k)) * (1 - t).ln()


def ref_outer(rp: float, R: float, k: float) -> Decimal:
    with localcontext() as ctx:
        ctx.prec = 60
        z = _d(k) * _d(rp) / _d(R)
        return _d(rp) + (_d(R) * (-z).exp() if z < 1000 else 0)


def ref_outer_inverse(rg: float, R: float, k: float) -> Decimal:
    """Newton on r + R exp(-k r / R) = r_g in 60 digits (monotone, convex: converges from r_g - R)."""
    with localcontext() as ctx:
        ctx.prec = 60
        r, Rd, kd, g = max(_d(rg) - _d(R), Decimal(0)), _d(R), _d(k), _d(rg)
        for _ in range(200):
            z = kd * r / Rd
            e = (-z).exp() if z < 1000 else Decimal(0)
            step = (r + Rd * e - g) / (1 - kd * e)
            r -= step
            if step == 0 or abs(step) <= abs(r) * Decimal("1e-50"):
                break
        return r


def rel_err(got: float, ref: Decimal) -> float:
    if ref == 0:
        return 0.0 if got == 0.0 else math.inf
    with localcontext() as ctx:
        ctx.prec = 60
        return float(abs((_d(got) - ref) / ref))


def physical(bound: float, k: float, *, radius: bool = False) -> bool:
    """Parameters inside the ranges of the accuracy claims (see ks_acc, theta_bs_acc, r_bs_acc)."""
    lo, hi = (1e-9, 1e3) if radius else (1e-6, math.pi / 2)
    return lo <= bound <= hi and k >= 1e-6


def ulp_gap(a: float, b: float) -> float:
    """An upper bound of the spacing of doubles at max(|a|, |b|), subnormals included."""
    return max(max(abs(a), abs(b)) * EPS, 5e-324)


def kappa_saturate(u: float) -> float:
    """Condition number (e^u - 1)/u of the saturating map's inverse at the image of u = k x / b."""
    if u == 0.0:
        return 1.0
    return math.inf if u > 700 else math.expm1(u) / u


# --------------------------------------------------------------------------------------------------
# images strictly inside their bounds


@SETTINGS
@given(tg=any_reals, theta_b=theta_bs, k=ks)
@example(tg=1e300, theta_b=math.pi / 2, k=0.999999)
@example(tg=-FMAX, theta_b=1e-300, k=0.5)
@example(tg=1e-300, theta_b=math.pi / 2, k=1e-300)
@example(tg=0.0, theta_b=0.3, k=0.5)
def test_angle_image_strictly_inside_cone(tg: float, theta_b: float, k: float) -> None:
    th = mp.angle_map(tg, theta_b, k)
    assert th.shape == ()
    assert -theta_b < th < theta_b
    assert np.sign(th) == np.sign(tg) or th == 0.0
    if tg == 0.0:
        assert th == 0.0


@SETTINGS
@given(rp=radii, r_b=r_bs, k=ks)
@example(rp=1e300, r_b=1e-300, k=0.999999)
@example(rp=1e300, r_b=1e300, k=0.5)
@example(rp=0.0, r_b=0.1, k=0.5)
def test_inner_image_strictly_inside_ball(rp: float, r_b: float, k: float) -> None:
    rg = mp.inner_radius(rp, r_b, k)
    assert 0.0 <= rg < r_b
    if rp == 0.0:
        assert rg == 0.0
    elif rg == 0.0:  # only when the exact image is below one subnormal spacing
        assert ref_saturate(rp, r_b, k) < _d(5e-324)


@SETTINGS
@given(rp=radii, r_b=r_bs, k=ks, delta=deltas)
@example(rp=1e300, r_b=1e300, k=0.999999, delta=1e300)
@example(rp=0.0, r_b=0.05, k=0.5, delta=0.01)
@example(rp=1e-300, r_b=1e-300, k=0.5, delta=0.0)
def test_outer_image_outside_margin(rp: float, r_b: float, k: float, delta: float) -> None:
    rg = om.outer_radius(rp, r_b, k, delta=delta)
    R = r_b + delta
    assert np.isfinite(rg)
    assert rg >= R
    if R > r_b:  # a positive margin that is representable next to r_b keeps the obstacle disc strictly out
        assert rg > r_b
    assert rg >= rp  # never pulls a point inwards
    if rp == 0.0:
        assert rg == R


@SETTINGS
@given(rp=radii, r_b=r_bs, k=ks)
def test_printed_outer_image_in_half_open_band(rp: float, r_b: float, k: float) -> None:
    rg = om.outer_radius_printed(rp, r_b, k)
    assert r_b < rg <= 2.0 * r_b
    if rp == 0.0:
        assert rg == 2.0 * r_b


def test_vectorized_shapes_and_huge_tiny_zero() -> None:
    x = np.array([[0.0, 1e-300, 1e300], [-0.0, -1e-300, -1e300]])
    th = mp.angle_map(x, 0.4, 0.3)
    assert th.shape == (2, 3)
    assert np.all(np.abs(th) < 0.4)
    assert th[0, 2] == np.nextafter(0.4, 0.0) and th[1, 2] == -np.nextafter(0.4, 0.0)
    assert th[0, 1] == pytest.approx(0.3e-300, rel=2 * EPS)  # slope k at zero, full relative precision
    np.testing.assert_allclose(mp.angle_inverse(th[:, :2], 0.4, 0.3), x[:, :2], rtol=RTOL, atol=0.0)
    r = np.abs(x)
    assert mp.inner_radius(r, 0.1, 0.3).shape == (2, 3)
    assert om.outer_radius(r, 0.1, 0.3).shape == (2, 3)
    assert om.outer_radius(r, 0.1, 0.3)[0, 2] == 1e300  # identity far away (tail effect)


# --------------------------------------------------------------------------------------------------
# accuracy against 60-digit references


@SETTINGS_DECIMAL
@given(x=st.floats(0.0, 1e300), b=theta_bs_acc, k=ks_acc)
def test_saturating_forward_accurate(x: float, b: float, k: float) -> None:
    got = float(mp.angle_map(x, b, k))
    ref = ref_saturate(x, b, k)
    if ref >= _d(float(np.nextafter(b, 0.0))):  # image rounds onto the bound: the documented one-ulp clamp
        assert got == np.nextafter(b, 0.0)
    elif float(ref) >= TINY:
        assert rel_err(got, ref) <= ACC
    else:  # subnormal image
        assert abs(got - float(ref)) <= 5e-324


@SETTINGS_DECIMAL
@given(frac=st.floats(0.0, 1.0, exclude_max=True), b=theta_bs_acc, k=ks_acc)
@example(frac=1.0 - EPS / 2, b=1.0, k=0.5)
def test_saturating_inverse_accurate(frac: float, b: float, k: float) -> None:
    y = min(frac * b, float(np.nextafter(b, 0.0)))
    got = float(mp.angle_inverse(y, b, k))
    ref = ref_saturate_inverse(y, b, k)
    if float(ref) >= TINY:
        assert rel_err(got, ref) <= ACC
    else:
        assert abs(got - float(ref)) <= 5e-324 / k


@SETTINGS_DECIMAL
@given(rp=st.floats(0.0, 1e6), R=r_bs_acc, k=ks)
@example(rp=1e-12, R=1.0, k=1.0 - 2**-40)
def test_outer_forward_accurate(rp: float, R: float, k: float) -> None:
    got = float(om.outer_radius(rp, R, k))
    assert rel_err(got, ref_outer(rp, R, k)) <= ACC


@SETTINGS_DECIMAL
@given(excess=st.floats(0.0, 1e6), R=r_bs_acc, k=ks)
@example(excess=1e-14, R=1.0, k=0.999)
@example(excess=0.0, R=1.0, k=0.5)
def test_outer_inverse_accurate(excess: float, R: float, k: float) -> None:
    rg = R + excess
    got = float(om.outer_radius_inverse(rg, R, k))
    ref = ref_outer_inverse(rg, R, k)
    if rg == R:
        assert got == 0.0
    else:
        assert rel_err(got, ref) <= ACC


# --------------------------------------------------------------------------------------------------
# round trips


@SETTINGS
@given(tg=any_reals, theta_b=theta_bs, k=ks)
@example(tg=1e-300, theta_b=1.0, k=0.5)
@example(tg=-2.0, theta_b=0.5, k=0.9)
@example(tg=1e300, theta_b=1.0, k=0.5)
def test_angle_round_trip(tg: float, theta_b: float, k: float) -> None:
    th = float(mp.angle_map(tg, theta_b, k))
    try:
        back = float(mp.angle_inverse(th, theta_b, k))
    except InputError:
        # only when the preimage of th overflows: (theta_b / k) * (-ln(1 - |th| / theta_b)) > max double
        lg = -math.log1p(-abs(th) / theta_b) if abs(th) / theta_b <= 0.5 else -math.log((theta_b - abs(th)) / theta_b)
        assert math.log(lg) + math.log(theta_b) - math.log(k) > math.log(FMAX) * (1 - 1e-12)
        return
    u = k * (abs(tg) / theta_b) if abs(tg) / theta_b < 1e300 else math.inf
    if physical(theta_b, k) and kappa_saturate(u) <= KAPPA_MAX:
        event("relative round trip checked")
        if abs(th) >= TINY:
            assert abs(back - tg) <= RTOL * abs(tg)
        else:  # subnormal image: one subnormal spacing, through the slope 1/k
            assert abs(back - tg) <= RTOL * abs(tg) + 5e-324 / k
    # backward stability everywhere
    again = float(mp.angle_map(back, theta_b, k))
    assert abs(again - th) <= 8 * ulp_gap(th, again)


@SETTINGS
@given(
    frac=st.floats(-1.0, 1.0, exclude_min=True, exclude_max=True),
    theta_b=theta_bs,
    k=st.floats(1e-6, 1.0, exclude_max=True),
)
@example(frac=1.0 - EPS / 2, theta_b=math.pi / 2, k=0.5)
@example(frac=1e-300, theta_b=math.pi / 2, k=0.5)
def test_angle_inverse_then_forward(frac: float, theta_b: float, k: float) -> None:
    th = frac * theta_b
    th = math.copysign(min(abs(th), float(np.nextafter(theta_b, 0.0))), th)
    again = float(mp.angle_map(mp.angle_inverse(th, theta_b, k), theta_b, k))
    if abs(th) >= TINY:
        assert abs(again - th) <= RTOL * abs(th)
    else:
        assert abs(again - th) <= 5e-324


@SETTINGS
@given(rp=radii, r_b=r_bs, k=ks)
@example(rp=1e-300, r_b=1e300, k=0.5)
@example(rp=3.0, r_b=1.0, k=0.99)
def test_inner_round_trip(rp: float, r_b: float, k: float) -> None:
    rg = float(mp.inner_radius(rp, r_b, k))
    try:
        back = float(mp.inner_radius_inverse(rg, r_b, k))
    except InputError:
        lg = -math.log1p(-rg / r_b) if rg / r_b <= 0.5 else -math.log((r_b - rg) / r_b)
        assert math.log(lg) + math.log(r_b) - math.log(k) > math.log(FMAX) * (1 - 1e-12)
        return
    q = rp / r_b
    u = k * q if q < 1e300 else math.inf
    if physical(r_b, k, radius=True) and kappa_saturate(u) <= KAPPA_MAX:
        event("relative round trip checked")
        if rg >= TINY:
            assert abs(back - rp) <= RTOL * rp
        else:
            assert abs(back - rp) <= RTOL * rp + 5e-324 / k
    again = float(mp.inner_radius(back, r_b, k))
    assert abs(again - rg) <= 8 * ulp_gap(rg, again)


@SETTINGS
@given(rp=radii, r_b=r_bs, k=ks, delta=deltas)
@example(rp=1e-300, r_b=1.0, k=0.5, delta=0.0)
@example(rp=1e-3, r_b=1.0, k=0.5, delta=0.1)
@example(rp=1e300, r_b=1e-300, k=0.5, delta=0.0)
def test_outer_round_trip(rp: float, r_b: float, k: float, delta: float) -> None:
    rg = float(om.outer_radius(rp, r_b, k, delta=delta))
    back = float(om.outer_radius_inverse(rg, r_b, k, delta=delta))
    assert back >= 0.0
    R = r_b + delta
    q = rp / R
    e = math.exp(-k * q) if q < 1e300 else 0.0
    kappa = math.inf if rp < 1e-290 else rg / rp / (1.0 - k * e)  # subnormal r_p: no relative claim
    if physical(r_b, k, radius=True) and delta <= 1e3 and kappa <= KAPPA_MAX:
        event("relative round trip checked")
        assert abs(back - rp) <= RTOL * rp
    if rp == 0.0:
        assert back == 0.0
    again = float(om.outer_radius(back, r_b, k, delta=delta))
    assert abs(again - rg) <= 8 * ulp_gap(rg, again)


@SETTINGS
@given(rp=radii, r_b=r_bs, k=ks)
def test_printed_outer_round_trip(rp: float, r_b: float, k: float) -> None:
    rg = float(om.outer_radius_printed(rp, r_b, k))
    back = float(om.outer_radius_printed_inverse(rg, r_b, k))
    # condition number of the printed inverse: (e^u + 1)/u, u = k r_p / r_b (r_g - r_b = r_b e^{-u} holds the
    # information and r_g is rounded at the scale of r_b: ill-conditioned both near r_p = 0 and far away)
    u = k * (rp / r_b) if rp / r_b < 1e300 else math.inf
    kappa = math.inf if (u == 0.0 or u > 700) else (math.exp(u) + 1.0) / u
    if physical(r_b, k, radius=True) and kappa <= KAPPA_MAX:
        event("relative round trip checked")
        assert abs(back - rp) <= RTOL * rp
    again = float(om.outer_radius_printed(back, r_b, k))
    assert abs(again - rg) <= 8 * ulp_gap(rg, again)


@SETTINGS
@given(e=st.floats(-300.0, 2.0), sign=st.sampled_from([1.0, -1.0]), b=theta_bs_acc, k=ks_acc)
def test_angle_round_trip_relative(e: float, sign: float, b: float, k: float) -> None:
    """Inputs spread over 300 decades below the bound: relative round trip 1e-12 wherever kappa <= 1e3."""
    tg = sign * b * 10.0**e
    u = k * abs(tg) / b
    if kappa_saturate(u) > KAPPA_MAX:
        return
    event("relative round trip checked")
    th = float(mp.angle_map(tg, b, k))
    back = float(mp.angle_inverse(th, b, k))
    sub = 0.0 if abs(th) >= TINY else 5e-324 / k  # subnormal image: one subnormal spacing through the slope 1/k
    assert abs(back - tg) <= RTOL * abs(tg) + sub


@SETTINGS
@given(e=st.floats(-300.0, 2.0), r_b=r_bs_acc, k=ks_acc)
def test_inner_round_trip_relative(e: float, r_b: float, k: float) -> None:
    rp = r_b * 10.0**e
    if kappa_saturate(k * rp / r_b) > KAPPA_MAX:
        return
    event("relative round trip checked")
    rg = float(mp.inner_radius(rp, r_b, k))
    back = float(mp.inner_radius_inverse(rg, r_b, k))
    sub = 0.0 if rg >= TINY else 5e-324 / k
    assert abs(back - rp) <= RTOL * rp + sub


@SETTINGS
@given(e=st.floats(-4.0, 6.0), r_b=r_bs_acc, k=ks_acc, delta_frac=st.floats(0.0, 1.0))
@example(e=-2.0, r_b=0.05, k=0.999, delta_frac=0.2)
def test_outer_round_trip_relative(e: float, r_b: float, k: float, delta_frac: float) -> None:
    delta = delta_frac * r_b
    R = r_b + delta
    rp = R * 10.0**e
    rg = float(om.outer_radius(rp, r_b, k, delta=delta))
    kappa = rg / rp / (1.0 - k * math.exp(-k * rp / R))
    if kappa > KAPPA_MAX:
        return
    event("relative round trip checked")
    back = float(om.outer_radius_inverse(rg, r_b, k, delta=delta))
    assert abs(back - rp) <= RTOL * rp


@SETTINGS
@given(e=st.floats(-4.0, 2.0), r_b=r_bs_acc, k=ks_acc)
def test_printed_outer_round_trip_relative(e: float, r_b: float, k: float) -> None:
    rp = r_b * 10.0**e
    u = k * rp / r_b
    if u == 0.0 or (math.exp(u) + 1.0) / u > KAPPA_MAX:
        return
    event("relative round trip checked")
    back = float(om.outer_radius_printed_inverse(om.outer_radius_printed(rp, r_b, k), r_b, k))
    assert abs(back - rp) <= RTOL * rp


# --------------------------------------------------------------------------------------------------
# monotonicity


def _check_monotone(f, a: float, b: float, ref, slack_ulps: int = 0) -> None:  # type: ignore[no-untyped-def]
    """a <= b: f(a) <= f(b) (+ slack_ulps ulps) in floating point; f(a) < f(b) when the exact gap exceeds 4 ulps."""
    fa, fb = float(f(a)), float(f(b))
    assert fa <= fb + slack_ulps * float(np.spacing(fb))
    with localcontext() as ctx:
        ctx.prec = 60
        gap = ref(b) - ref(a)
    if gap > _d(4 * ulp_gap(fa, fb)) + _d(5e-324):
        event("strict order checked")
        assert fa < fb


@SETTINGS_DECIMAL
@given(a=any_reals, b=any_reals, theta_b=theta_bs, k=ks)
def test_angle_monotone(a: float, b: float, theta_b: float, k: float) -> None:
    a, b = min(a, b), max(a, b)

    def ref(x: float) -> Decimal:
        return ref_saturate(abs(x), theta_b, k).copy_sign(_d(x)) if x != 0 else Decimal(0)

    _check_monotone(lambda x: mp.angle_map(x, theta_b, k), a, b, ref)


@SETTINGS_DECIMAL
@given(a=radii, b=radii, r_b=r_bs, k=ks, delta=deltas)
def test_radial_maps_monotone(a: float, b: float, r_b: float, k: float, delta: float) -> None:
    a, b = min(a, b), max(a, b)
    _check_monotone(lambda x: mp.inner_radius(x, r_b, k), a, b, lambda x: ref_saturate(x, r_b, k))
    R = r_b + delta

    def outer(x: float) -> np.ndarray:
        return om.outer_radius(x, r_b, k, delta=delta)

    _check_monotone(outer, a, b, lambda x: ref_outer(x, R, k), slack_ulps=1)


def _consecutive(x0: float, n: int = 2000) -> np.ndarray:
    """2 n + 1 consecutive doubles centred on x0 (x0 > 0, away from a power of two)."""
    return x0 + np.arange(-n, n + 1) * np.spacing(x0)


def _steps_in_ulps(y: np.ndarray) -> np.ndarray:
    return np.diff(y) / np.spacing(np.maximum(np.abs(y[1:]), TINY))


@pytest.mark.parametrize("k", [0.05, 0.5, 0.9, 0.999, 0.999999])
@pytest.mark.parametrize("b", [0.013, 0.7, 1.0])
def test_monotone_on_consecutive_doubles(k: float, b: float) -> None:
    """Sweeps of consecutive doubles, including every switch between formulas inside the module.

    The saturating maps (6)/(7 inner), their inverses and the printed outer form are compositions of monotone
    operations and rounding: exactly non-decreasing (non-increasing for the printed form). The monotone outer
    map is a sum of an increasing and a decreasing part (slope 1 - k exp(-u) < 1) and its inverse is polished
    by Newton steps: they may step back by one ulp between consecutive doubles, never more.
    """
    # u = k x / b crosses TINY and 1/2 (series switch of the outer excess); x = b; deep in saturation
    for x0 in (TINY * b / k * 3, 0.5 * b / k, 1e-8 * b, b, 3 * b / k, 40 * b / k):
        xs = _consecutive(x0)
        assert np.all(np.diff(mp.inner_radius(xs, b, k)) >= 0.0)
        tb = min(b, math.pi / 2)
        assert np.all(np.diff(mp.angle_map(xs, tb, k)) >= 0.0)
        assert np.all(np.diff(om.outer_radius_printed(xs, b, k)) <= 0.0)
        y = om.outer_radius(xs, b, k)
        assert _steps_in_ulps(y).min() >= -1.0
        yi = mp.inner_radius(xs, b, k)
        assert np.all(np.diff(mp.inner_radius_inverse(np.unique(yi), b, k)) >= 0.0)
        ys = _consecutive(float(y[xs.size // 2]))
        ys = ys[ys >= b]
        assert _steps_in_ulps(om.outer_radius_inverse(ys, b, k)).min() >= -1.0
    # inverse switches: t = y / b crosses 1/2 and TINY; up to the largest double below the bound
    for y0 in (0.5 * b, TINY * b * 3, float(np.nextafter(b, 0.0)) - 2000 * float(np.spacing(b / 2))):
        ys = _consecutive(y0)
        ys = ys[ys < b]
        assert np.all(np.diff(mp.inner_radius_inverse(ys, b, k)) >= 0.0)


@SETTINGS
@given(a=radii, b=radii, r_b=r_bs, k=ks)
def test_printed_outer_reverses_order(a: float, b: float, r_b: float, k: float) -> None:
    """The printed outer (7) is non-increasing, strictly where resolvable; the monotone form is not."""
    a, b = min(a, b), max(a, b)
    fa, fb = float(om.outer_radius_printed(a, r_b, k)), float(om.outer_radius_printed(b, r_b, k))
    assert fa >= fb
    with localcontext() as ctx:
        ctx.prec = 60
        za, zb = _d(k) * _d(a) / _d(r_b), _d(k) * _d(b) / _d(r_b)
        ea = (-za).exp() if za < 1000 else Decimal(0)
        eb = (-zb).exp() if zb < 1000 else Decimal(0)
        gap = _d(r_b) * (ea - eb)
    if gap > _d(4 * ulp_gap(fa, fb)):
        event("strict order checked")
        assert fa > fb
        assert float(om.outer_radius(a, r_b, k)) < float(om.outer_radius(b, r_b, k))


def test_printed_outer_turns_an_approach_inside_out() -> None:
    """A straight approach to an obstacle: the printed map sends the nearest point farthest away."""
    r_b, k = 0.05, 0.5
    rp = np.array([0.0, 0.01, 0.05, 0.2, 1.0])  # moving away from the obstacle centre
    printed = om.outer_radius_printed(rp, r_b, k)
    monotone = om.outer_radius(rp, r_b, k)
    assert printed[0] == pytest.approx(2 * r_b, rel=1e-15)  # the centre goes to 2 r_b ...
    assert printed[-1] == pytest.approx(r_b * (1 + math.exp(-10.0)), rel=1e-15)  # ... far points to r_b
    assert np.all(np.diff(printed) < 0.0)
    assert np.all(np.diff(monotone) > 0.0)
    assert monotone[0] == r_b and monotone[-1] == pytest.approx(1.0 + r_b * math.exp(-10.0), rel=1e-15)


# --------------------------------------------------------------------------------------------------
# the boundary: clipping is explicit


@pytest.mark.parametrize("theta", [0.4, 0.5, -0.4, -7.0])
def test_angle_inverse_on_or_beyond_bound(theta: float) -> None:
    tb, k = 0.4, 0.3
    with pytest.raises(InputError) as info:
        mp.angle_inverse(np.array([0.1, theta]), tb, k)
    assert info.value.field == "theta" and "clip=True" in info.value.expected
    got = mp.angle_inverse(np.array([0.1, theta]), tb, k, clip=True)
    edge = float(mp.angle_inverse(np.nextafter(tb, 0.0), tb, k))
    assert got[1] == math.copysign(edge, theta)  # clipped to the largest double inside the cone
    below = tb - float(np.nextafter(tb, 0.0))
    assert edge == pytest.approx(-(tb / k) * math.log(below / tb), rel=1e-15)  # about 36.7 tb / k
    assert got[0] == mp.angle_inverse(0.1, tb, k)  # other entries untouched
    # clipping keeps the inverse monotone: the clipped value is the largest preimage
    inside = mp.angle_inverse(np.linspace(0.0, float(np.nextafter(tb, 0.0)), 1001), tb, k)
    assert np.all(np.diff(inside) >= 0.0) and inside[-1] == edge


@pytest.mark.parametrize("r_g", [0.1, 0.2, 1e300])
def test_inner_inverse_on_or_beyond_bound(r_g: float) -> None:
    r_b, k = 0.1, 0.5
    with pytest.raises(InputError) as info:
        mp.inner_radius_inverse(r_g, r_b, k)
    assert info.value.field == "r_g"
    got = float(mp.inner_radius_inverse(r_g, r_b, k, clip=True))
    assert got == float(mp.inner_radius_inverse(np.nextafter(r_b, 0.0), r_b, k))
    assert math.isfinite(got) and mp.inner_radius(got, r_b, k) < r_b


def test_outer_inverse_inside_margin() -> None:
    r_b, k, delta = 0.05, 0.5, 0.01
    R = r_b + delta
    assert float(om.outer_radius_inverse(R, r_b, k, delta=delta)) == 0.0  # on the closed bound: fine
    for rg in (0.0, r_b, float(np.nextafter(R, 0.0))):
        with pytest.raises(InputError) as info:
            om.outer_radius_inverse(rg, r_b, k, delta=delta)
        assert info.value.field == "r_g" and "clip=True" in info.value.expected
        assert float(om.outer_radius_inverse(rg, r_b, k, delta=delta, clip=True)) == 0.0


def test_printed_outer_inverse_bounds() -> None:
    r_b, k = 0.05, 0.5
    assert float(om.outer_radius_printed_inverse(2 * r_b, r_b, k)) == 0.0
    for rg in (r_b, 0.01, 2 * r_b * (1 + 1e-9)):
        with pytest.raises(InputError):
            om.outer_radius_printed_inverse(rg, r_b, k)
    assert float(om.outer_radius_printed_inverse(0.3, r_b, k, clip=True)) == 0.0
    low = float(om.outer_radius_printed_inverse(r_b, r_b, k, clip=True))
    assert low == float(om.outer_radius_printed_inverse(np.nextafter(r_b, np.inf), r_b, k))
    assert low > 30 * r_b / k


def test_safety_margin_is_r_b_plus_delta() -> None:
    rp = np.array([0.0, 0.02, 0.3])
    R = 0.05 + 0.01  # computed in floating point, as the module does
    np.testing.assert_array_equal(om.outer_radius(rp, 0.05, 0.4, delta=0.01), om.outer_radius(rp, R, 0.4))
    assert np.all(om.outer_radius(rp, 0.05, 0.4, delta=0.01) > om.outer_radius(rp, 0.05, 0.4))


# --------------------------------------------------------------------------------------------------
# validation


@pytest.mark.parametrize("k", [0.0, 1.0, -0.5, 1.5, math.nan, math.inf, "a", None])
def test_bad_k(k: object) -> None:
    for call in (
        lambda: mp.angle_map(0.1, 0.3, k),  # type: ignore[arg-type]
        lambda: mp.inner_radius_inverse(0.01, 0.1, k),  # type: ignore[arg-type]
        lambda: om.outer_radius(0.01, 0.1, k),  # type: ignore[arg-type]
    ):
        with pytest.raises(InputError) as info:
            call()
        assert info.value.field == "k"


@pytest.mark.parametrize("theta_b", [0.0, -0.1, math.pi / 2 + 1e-9, math.nan, math.inf])
def test_bad_theta_b(theta_b: float) -> None:
    with pytest.raises(InputError) as info:
        mp.angle_map(0.1, theta_b, 0.5)
    assert info.value.field == "theta_b"
    mp.angle_map(0.1, math.pi / 2, 0.5)  # the half-plane cone is allowed


@pytest.mark.parametrize("r_b", [0.0, -1.0, math.inf, math.nan, 2e300])
def test_bad_r_b(r_b: float) -> None:
    for call in (lambda: mp.inner_radius(0.1, r_b, 0.5), lambda: om.outer_radius_inverse(1.0, r_b, 0.5)):
        with pytest.raises(InputError) as info:
            call()
        assert info.value.field == "r_b"


def test_bad_inputs() -> None:
    with pytest.raises(InputError, match="delta"):
        om.outer_radius(0.1, 0.05, 0.5, delta=-1e-3)
    with pytest.raises(InputError, match="theta_g"):
        mp.angle_map([0.1, math.nan], 0.3, 0.5)
    with pytest.raises(InputError, match="theta_g"):
        mp.angle_map(math.inf, 0.3, 0.5)
    with pytest.raises(InputError, match="r_p"):
        mp.inner_radius([0.1, -1e-9], 0.05, 0.5)
    with pytest.raises(InputError, match="r_p"):
        om.outer_radius(FMAX, 1e300, 1e-300)  # the image overflows
    with pytest.raises(InputError, match="r_b"):
        mp.inner_radius(0.1, 1e-310, 0.5)  # a subnormal bound leaves no room for the image
    with pytest.raises(InputError, match="theta_b"):
        mp.angle_map(0.1, 1e-310, 0.5)
    with pytest.raises(InputError, match="r_g"):
        mp.inner_radius_inverse(-1e-9, 0.05, 0.5, clip=True)  # a negative radius is not clipped
    with pytest.raises(InputError, match="x_p"):
        pm.outer_map_points([[0.1, 0.2]], [0.1, 0.2], 0.05, 0.5)  # the centre has no image direction
    with pytest.raises(InputError, match="center"):
        pm.inner_map_points(np.zeros((4, 2)), np.zeros((3, 2)), 0.05, 0.5)


def test_inverse_overflow_is_an_input_error() -> None:
    with pytest.raises(InputError, match="overflows"):
        mp.inner_radius_inverse(0.5e300, 1e300, 1e-10)


# --------------------------------------------------------------------------------------------------
# point maps


coords = st.floats(-1.0, 1.0)


@SETTINGS
@given(
    pts=st.lists(st.tuples(coords, coords), min_size=1, max_size=6),
    c=st.tuples(coords, coords),
    r_b=st.floats(0.01, 1.0),
    k=st.floats(0.1, 0.9),
)
def test_inner_points_tube_and_round_trip(
    pts: list[tuple[float, float]], c: tuple[float, float], r_b: float, k: float
) -> None:
    x = np.array(pts)
    centers = np.array(c) + 0.1 * x[::-1]  # one centre per point: a tube around a path
    xg = pm.inner_map_points(x, centers, r_b, k)
    assert xg.shape == x.shape
    d = np.linalg.norm(xg - centers, axis=1)
    # the image radius is < r_b; adding the offset to the centre rounds at the scale of the centre
    assert np.all(d < r_b + 4 * EPS * (np.abs(centers).max(axis=1) + r_b))
    back = pm.inner_inverse_points(xg, centers, r_b, k, clip=True)
    u = k * np.linalg.norm(x - centers, axis=1) / r_b
    ok = u <= 5.0  # kappa <= 30, and e^u / k <= 1.5e3 amplifies the centre's rounding below 1e-12
    scale = np.abs(x).max(axis=1) + np.abs(centers).max(axis=1)
    assert np.all(np.linalg.norm(back - x, axis=1)[ok] <= RTOL * scale[ok])


@SETTINGS
@given(
    pts=st.lists(st.tuples(coords, coords), min_size=1, max_size=6),
    c=st.tuples(coords, coords),
    r_b=st.floats(0.01, 0.5),
    k=st.floats(0.1, 0.9),
    delta=st.floats(0.0, 0.05),
)
def test_outer_points_keep_out_and_round_trip(
    pts: list[tuple[float, float]], c: tuple[float, float], r_b: float, k: float, delta: float
) -> None:
    x = np.array(pts)
    centre = np.array(c)
    keep = np.linalg.norm(x - centre, axis=1) > 0.0
    x = x[keep]
    if x.size == 0:
        return
    xg = pm.outer_map_points(x, centre, r_b, k, delta=delta)
    d = np.linalg.norm(xg - centre, axis=1)
    assert np.all(d >= (r_b + delta) - 4 * EPS * (np.abs(centre).max() + d))
    back = pm.outer_inverse_points(xg, centre, r_b, k, delta=delta, clip=True)
    scale = np.abs(x).max(axis=1) + np.abs(centre).max() + r_b + delta
    # slope of the outer map >= 1 - k >= 0.1: the centre's rounding is amplified at most 10 times
    assert np.all(np.linalg.norm(back - x, axis=1) <= RTOL * scale)


def test_points_at_centre_and_inside_margin() -> None:
    c = np.array([0.2, -0.1])
    np.testing.assert_array_equal(pm.inner_map_points(c, c, 0.1, 0.5), c)
    np.testing.assert_array_equal(pm.inner_inverse_points(c, c, 0.1, 0.5), c)
    with pytest.raises(InputError) as info:
        pm.outer_inverse_points(c + np.array([0.01, 0.0]), c, 0.05, 0.5, delta=0.01)
    assert info.value.field == "x_g"
    np.testing.assert_array_equal(
        pm.outer_inverse_points(c + np.array([0.01, 0.0]), c, 0.05, 0.5, delta=0.01, clip=True), c
    )
    with pytest.raises(InputError) as info:
        pm.inner_inverse_points(c + np.array([0.0, 0.1]), c, 0.1, 0.5)
    assert info.value.field == "x_g"
    far = pm.inner_inverse_points(c + np.array([0.0, 0.1]), c, 0.1, 0.5, clip=True)
    assert far[0] == c[0] and far[1] > c[1] + 30 * 0.1 / 0.5 * 0.9


def test_wrap_angle() -> None:
    a = np.array([0.0, math.pi, -math.pi, 3 * math.pi / 2, -1e3])
    w = mp.wrap_angle(a)
    assert np.all((w >= -math.pi) & (w < math.pi))
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-12)
    np.testing.assert_allclose(np.sin(w), np.sin(a), atol=1e-12)
