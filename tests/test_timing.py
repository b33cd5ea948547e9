"""Time parametrization under speed and acceleration limits."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.timing import min_jerk_along, min_jerk_duration, stretch_factor


@pytest.mark.parametrize(("length", "v_max", "a_max"), [(0.1, 0.05, 0.25), (0.01, 0.05, 0.01), (0.3, 0.02, 5.0)])
def test_min_jerk_meets_the_limits_with_one_of_them_tight(length: float, v_max: float, a_max: float) -> None:
    dur = min_jerk_duration(length, v_max, a_max)
    t, p = min_jerk_along(np.array([[0.0, 0.0], [length * 0.6, length * 0.8]]), dur, 4001)
    v = np.gradient(p, t, axis=0)
    a = np.gradient(v, t, axis=0)
    speed, acc = np.linalg.norm(v, axis=1).max(), np.linalg.norm(a, axis=1).max()
    assert speed <= v_max * (1 + 1e-4) and acc <= a_max * (1 + 1e-3)
    assert max(speed / v_max, acc / a_max) > 0.99  # the shortest such duration
    assert np.allclose(p[-1], [length * 0.6, length * 0.8])


def test_zero_length_move_takes_no_time() -> None:
    assert min_jerk_duration(0.0, 0.05, 0.25) == 0.0


def test_stretch_factor_brings_a_fast_path_within_limits() -> None:
    t = np.linspace(0, 1, 500)
    xy = np.column_stack([0.2 * np.sin(2 * np.pi * t), np.zeros_like(t)])
    c = stretch_factor(t, xy, 0.05, 0.25)
    v = np.gradient(xy, c * t, axis=0)
    a = np.gradient(v, c * t, axis=0)
    assert np.linalg.norm(v, axis=1).max() <= 0.05 + 1e-12
    assert np.linalg.norm(a, axis=1).max() <= 0.25 + 1e-12
    assert stretch_factor(t, 1e-6 * xy, 0.05, 0.25) == 1.0
