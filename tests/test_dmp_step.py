"""DMP.step: stepwise execution agrees with the exact rollout, a held coupling moves the rest point,
moving goals follow the piecewise system, obstacle coupling steers clear, bad input is named."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tooltransfer.dmp import DMP, InputError
from tooltransfer.dmp.coupling import obstacle_coupling


def fitted(scaling: str = "none", beta: float | None = None) -> DMP:
    t = np.linspace(0.0, 1.3, 300)
    s = t / t[-1]
    x = np.stack([0.12 * s + 0.03 * np.sin(np.pi * s), 0.04 * s + 0.05 * np.sin(np.pi * s)], axis=1)
    return DMP(2, n_basis=30, beta_z=beta, scaling=scaling).fit(t, x)  # type: ignore[arg-type]


def run(d: DMP, times: np.ndarray, **start: object) -> tuple[np.ndarray, np.ndarray]:
    state = d.start(**start)  # type: ignore[arg-type]
    xs, vs = [state.x], [state.v]
    for a, b in pairwise(times):
        state = d.step(state, b - a)
        xs.append(state.x)
        vs.append(state.v)
    return np.array(xs), np.array(vs)


@pytest.mark.parametrize("beta", [None, 4.0, 10.0])  # critical, over- and under-damped
@pytest.mark.parametrize("scaling", ["none", "amplitude"])
def test_uncoupled_steps_agree_with_exact_rollout(beta: float | None, scaling: str) -> None:
    d = fitted(scaling, beta)
    rng = np.random.default_rng(3)
    # uneven steps, from much shorter to longer than the exact rollout's sub-interval, past tau
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(1e-4, 0.05, 60))])
    kw = {"x0": [0.01, -0.02], "g": [0.15, 0.04], "v0": [0.05, -0.03], "tau": 1.1}
    x, v = run(d, times, **kw)
    ref = d.rollout(times, **kw)  # type: ignore[arg-type]
    np.testing.assert_allclose(x, ref.x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(v, ref.v, rtol=0, atol=1e-9)


def test_step_at_control_rate_agrees_with_rollout() -> None:
    d = fitted()
    times = np.arange(0.0, 1.5 + 1e-12, 1e-3)  # 1 kHz, the Omni's servo rate
    x, v = run(d, times)
    ref = d.rollout(times)
    assert np.abs(x - ref.x).max() < 1e-9
    assert np.abs(v - ref.v).max() < 1e-9


def test_held_coupling_is_a_shifted_goal() -> None:
    d = fitted()
    c = np.array([0.4, -0.7])
    times = np.linspace(0.0, 1.4, 71)
    state = d.start()
    xs = [state.x]
    for a, b in pairwise(times):
        state = d.step(state, b - a, coupling=c)
        xs.append(state.x)
    ref = d.rollout(times, g=d.g + c / (d.alpha_z * d.beta_z))
    np.testing.assert_allclose(np.array(xs), ref.x, rtol=0, atol=1e-9)


def test_moving_goal_follows_the_piecewise_system() -> None:
    d = fitted("amplitude")
    g1, g2, t_switch = d.g.copy(), d.g + np.array([0.03, -0.02]), 0.6
    times = np.linspace(0.0, 3.0, 151)
    state, xs = d.start(), [d.x0.copy()]
    for a, b in pairwise(times):
        state = d.step(state, b - a, goal=g2 if a >= t_switch - 1e-12 else None)
        xs.append(state.x)
    assert np.array_equal(state.g, g2)
    # reference: DOP853 on the same system, the goal (and the scaling it sets) switched at t_switch
    m1, m2 = (d.scaling_matrix(d.x0, g) for g in (g1, g2))

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        g, m = (g1, m1) if t < t_switch else (g2, m2)
        x, v = y[:2], y[2:]
        f = (d.basis(np.array([t])) @ d.weights @ m.T)[0]
        return np.concatenate([v, (d.alpha_z * (d.beta_z * (g - x) - d.tau * v) + f) / d.tau**2])

    first = times <= t_switch + 1e-12
    kw = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-14}
    a = solve_ivp(rhs, (0.0, t_switch), np.concatenate([d.x0, np.zeros(2)]), t_eval=times[first], **kw)
    b = solve_ivp(rhs, (t_switch, times[-1]), a.y[:, -1], t_eval=times[~first], **kw)
    ref = np.hstack([a.y, b.y])[:2].T
    np.testing.assert_allclose(np.array(xs), ref, rtol=0, atol=1e-8)
    assert np.linalg.norm(xs[-1] - g2) < 0.02 * np.linalg.norm(g2 - g1) + 1e-3


def test_obstacle_coupling_steers_clear_and_still_reaches_the_goal() -> None:
    t = np.linspace(0.0, 1.0, 200)
    d = DMP(2, n_basis=10).fit(t, np.stack([0.2 * t, 0.0 * t], axis=1))
    obstacle = np.array([0.1, 0.002])
    times = np.arange(0.0, 3.0, 4e-3)
    free, _ = run(d, times)
    state, xs = d.start(), [d.x0.copy()]
    for a, b in pairwise(times):
        c = obstacle_coupling(state.x, state.v, obstacle, state.tau)
        state = d.step(state, b - a, coupling=c)
        xs.append(state.x)
    coupled = np.array(xs)
    clear_free = np.linalg.norm(free - obstacle, axis=1).min()
    clear_coupled = np.linalg.norm(coupled - obstacle, axis=1).min()
    assert clear_free < 0.0025
    assert clear_coupled > 4 * clear_free
    assert np.linalg.norm(coupled[-1] - d.g) < 1e-3


def test_obstacle_coupling_turns_away_and_vanishes_behind() -> None:
    c = obstacle_coupling([0.0, 0.0], [1.0, 0.1], [1.0, 0.0], 1.0)
    assert c[1] > 0  # heading left of the obstacle: pushed further left
    assert np.allclose(obstacle_coupling([0.0, 0.0], [-1.0, 0.0], [1.0, 0.0], 1.0), 0.0)
    c3 = obstacle_coupling([0.0, 0.0, 0.0], [1.0, 0.0, -0.1], [1.0, 0.0, 0.0], 1.0)
    assert c3[2] < 0 and abs(c3[1]) < 1e-15


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [({"dt": 0.0}, "dt"), ({"dt": float("nan")}, "dt"), ({"dt": 0.01, "goal": [1.0]}, "goal"),
     ({"dt": 0.01, "coupling": [0.0, np.inf]}, "coupling")],
)
def test_bad_step_input_is_named(kwargs: dict[str, object], field: str) -> None:
    d = fitted()
    with pytest.raises(InputError, match=field):
        d.step(d.start(), **kwargs)  # type: ignore[arg-type]
