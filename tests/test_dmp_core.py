"""DMP core: fit/rollout reproduction, affine rollout, exact vs RK4, scaling, skill files, bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tooltransfer.dmp import DMP, InputError, SkillFileError
from tooltransfer.problems.fit_cases import l_path


def smooth_path(seed: int, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0 + rng.uniform(0, 1), n)
    s = (t - t[0]) / (t[-1] - t[0])
    a = rng.uniform(-0.1, 0.1, (3, 2))
    x = np.stack(
        [a[0, d] * s + a[1, d] * np.sin(np.pi * s) + a[2, d] * (1 - np.cos(2 * np.pi * s)) for d in range(2)], 1
    )
    return t, x


@settings(max_examples=15, deadline=None, derandomize=True)
@given(st.integers(0, 10_000), st.sampled_from(["forcing", "trajectory"]))
def test_fit_then_rollout_reproduces(seed: int, method: str) -> None:
    t, x = smooth_path(seed)
    d = DMP(2, n_basis=50).fit(t, x, method=method)
    v0 = np.gradient(x, t, axis=0)[0]
    r = d.rollout(t, x0=x[0], g=x[-1], v0=v0, tau=t[-1] - t[0])
    length = np.linalg.norm(np.diff(x, axis=0), axis=1).sum()
    rmse = np.sqrt(np.mean(np.sum((r.x - x) ** 2, axis=1)))
    assert rmse < 1e-3 * length


def test_rollout_is_affine_in_weights() -> None:
    t, x = smooth_path(1)
    d = DMP(2, n_basis=20).fit(t, x)
    rng = np.random.default_rng(0)
    w1, w2 = rng.normal(size=(2, 20, 2))
    a = 0.3
    tt = np.linspace(0, 1.5, 301)
    r1, r2 = d.rollout(tt, weights=w1), d.rollout(tt, weights=w2)
    r12 = d.rollout(tt, weights=a * w1 + (1 - a) * w2)
    np.testing.assert_allclose(r12.x, a * r1.x + (1 - a) * r2.x, atol=1e-12)
    aff = d.affine(tt)
    np.testing.assert_allclose(aff.positions(w1.ravel()), r1.x, atol=1e-13)
    np.testing.assert_allclose(aff.velocities(w1.ravel()), r1.v, atol=1e-12)


@pytest.mark.parametrize("beta", [None, 4.0, 10.0])  # critical, over- and under-damped
def test_exact_rollout_agrees_with_rk4(beta: float | None) -> None:
    t, x = smooth_path(2)
    d = DMP(2, n_basis=30, beta_z=beta).fit(t, x)
    tt = np.linspace(0, d.tau, 201)
    v0 = np.array([0.05, -0.02])
    ex = d.rollout(tt, v0=v0)
    rk = d.rollout(tt, v0=v0, method="rk4", rk4_step=2e-4)
    assert np.abs(ex.x - rk.x).max() < 1e-8
    assert np.abs(ex.v - rk.v).max() < 1e-7
    np.testing.assert_allclose(ex.v[0], v0, atol=1e-14)  # start velocity honoured


def test_coarse_grid_samples_match_fine_grid() -> None:
    t, x = smooth_path(3)
    d = DMP(2, n_basis=40).fit(t, x)
    fine = d.rollout(np.linspace(0, d.tau, 1001))
    coarse = d.rollout(np.linspace(0, d.tau, 11))
    np.testing.assert_allclose(coarse.x, fine.x[::100], atol=1e-12)


def test_goal_is_reached() -> None:
    t, x = l_path(500)
    d = DMP(2, n_basis=50).fit(t, x)
    r = d.rollout(np.linspace(0, 3 * d.tau, 600), x0=x[0], g=x[-1])
    assert np.linalg.norm(r.x[-1] - x[-1]) < 1e-6
    assert np.linalg.norm(r.v[-1]) < 1e-5


def test_multi_demo_fit_different_lengths_and_durations() -> None:
    t1, x1 = l_path(300, duration=3.0)
    t2, x2 = l_path(500, duration=5.0)
    d = DMP(2, n_basis=50).fit([t1, t2], [x1, x2])
    assert d.tau == pytest.approx(4.0)
    r = d.rollout(t1, x0=x1[0], g=x1[-1], tau=3.0)
    assert np.sqrt(np.mean(np.sum((r.x - x1) ** 2, 1))) < 1e-3 * 0.18


@pytest.mark.parametrize("mode", ["amplitude", "similarity"])
def test_scaling_modes_generalise_to_scaled_task(mode: str) -> None:
    t, x = smooth_path(4)
    x = x + np.array([0.0, 0.0]) if mode == "similarity" else x
    d = DMP(2, n_basis=50, scaling=mode).fit(t, x)
    x0, g = x[0], x[-1]
    scale = 2.0
    r = d.rollout(t, x0=scale * x0, g=scale * g, v0=scale * np.gradient(x, t, axis=0)[0])
    length = np.linalg.norm(np.diff(x, axis=0), axis=1).sum()
    assert np.sqrt(np.mean(np.sum((r.x - scale * x) ** 2, 1))) < 2e-3 * length


def test_similarity_is_rotation_equivariant() -> None:
    t, x = smooth_path(5)
    d = DMP(2, n_basis=50, scaling="similarity").fit(t, x)
    c, s = np.cos(0.7), np.sin(0.7)
    rot = np.array([[c, -s], [s, c]])
    r0 = d.rollout(t, x0=x[0], g=x[-1])
    r1 = d.rollout(t, x0=rot @ x[0], g=rot @ x[-1])
    np.testing.assert_allclose(r1.x, r0.x @ rot.T, atol=1e-12)


def test_amplitude_rejects_degenerate_dimension() -> None:
    t = np.linspace(0, 1, 100)
    x = np.stack([np.sin(np.pi * t) * 0.05, 0.1 * t], 1)  # x starts and ends at 0
    with pytest.raises(InputError, match="scaling"):
        DMP(2, scaling="amplitude").fit(t, x)


def test_skill_file_round_trip_and_errors(tmp_path) -> None:
    t, x = smooth_path(6)
    d = DMP(2, n_basis=25, scaling="similarity").fit(t, x, method="trajectory")
    p = tmp_path / "skill.json"
    d.save(str(p))
    e = DMP.load(str(p))
    tt = np.linspace(0, d.tau, 50)
    np.testing.assert_array_equal(e.rollout(tt).x, d.rollout(tt).x)
    data = json.loads(p.read_text())
    data["format"] = "tooltransfer.dmp/99"
    p.write_text(json.dumps(data))
    with pytest.raises(SkillFileError, match="version"):
        DMP.load(str(p))
    p.write_text("{not json")
    with pytest.raises(SkillFileError, match="JSON"):
        DMP.load(str(p))
    data["format"] = "tooltransfer.dmp/1"
    data["weights"] = [[1.0]]
    p.write_text(json.dumps(data))
    with pytest.raises(SkillFileError, match="weights"):
        DMP.load(str(p))


@pytest.mark.parametrize(
    ("t", "x", "field"),
    [
        (np.linspace(0, 1, 10), np.full((10, 2), np.nan), "X"),
        (np.linspace(0, 1, 10), np.zeros((10, 3)), "X"),
        (np.linspace(0, 1, 2), np.zeros((2, 2)), "t"),
        (np.array([0.0, 0.5, 0.5, 1.0]), np.zeros((4, 2)), "t"),
    ],
)
def test_bad_fit_input_names_field(t, x, field) -> None:
    with pytest.raises(InputError) as exc:
        DMP(2).fit(t, x)
    assert exc.value.field.startswith(field)


def test_bad_constructor_input() -> None:
    with pytest.raises(InputError, match="n_basis"):
        DMP(2, n_basis=0)
    with pytest.raises(InputError, match="scaling"):
        DMP(2, scaling="bogus")  # type: ignore[arg-type]
