"""SS skill learning: superposition (18), the pure tool skill, virtual motions, the skills file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tooltransfer.dmp.primitive import DMP
from tooltransfer.errors import InputError, SkillFileError
from tooltransfer.planner.learning.switch_skill import decompose
from tooltransfer.planner.learning.virtual_motion import virtual_motion
from tooltransfer.planner.planning.ss import DemoSwitch, SwitchSkill, learn_switch_skill
from tooltransfer.planner.planning.ss.synthetic import synthetic_switches
from tooltransfer.tools.objects import Disc


@pytest.fixture(scope="module")
def demos() -> list[DemoSwitch]:
    return synthetic_switches(5, seed=3)


def test_superposition_eq18_is_exact_for_dmps_sharing_a_phase() -> None:
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1.3, 120)
    d_t, d_o = DMP(2, n_basis=20), DMP(2, n_basis=20)
    d_t.weights, d_o.weights = rng.normal(0, 50, (20, 2)), rng.normal(0, 50, (20, 2))
    x_o = rng.normal(0, 0.05, 2)
    x0t, gt, x0o, go = x_o, rng.normal(0, 0.05, 2), x_o, rng.normal(0, 0.05, 2)
    k1, k2 = np.array([1.7, -0.4]), np.array([0.6, 2.1])
    xt = d_t.rollout(t, x0=x0t, g=gt, tau=1.3).x
    xo = d_o.rollout(t, x0=x0o, g=go, tau=1.3).x
    # (10): x - x_o = k1 (x^t - x_o) + k2 (x^o - x_o); (18): f = k1 f^t + k2 f^o
    g = x_o + k1 * (gt - x_o) + k2 * (go - x_o)
    x = d_t.rollout(t, x0=x_o, g=g, tau=1.3, weights=d_t.weights * k1 + d_o.weights * k2).x
    np.testing.assert_allclose(x - x_o, k1 * (xt - x_o) + k2 * (xo - x_o), rtol=0, atol=1e-12)


def test_pure_tool_skill_equals_the_dmp_fitted_on_x_minus_xo(demos: list[DemoSwitch]) -> None:
    skill = learn_switch_skill(demos, virtual="arch", n_basis=25)
    parts = [decompose(d, "arch", skill.clearance) for d in demos]
    direct = DMP(2, n_basis=25).fit([p.t for p in parts], [p.x_tool for p in parts])
    scale = np.abs(direct.weights).max()
    np.testing.assert_allclose(skill.dmp_t.weights, direct.weights, rtol=0, atol=1e-9 * scale)
    # and the learned x is reproduced by rolling the recombined skill out (k1 = k2 = I)
    t = parts[0].t
    x = skill.dmp_x.rollout(t, x0=np.zeros(2), g=skill.dmp_x.g, tau=skill.tau).x
    xr = skill.dmp_t.rollout(t, x0=np.zeros(2), g=skill.dmp_x.g, tau=skill.tau,
                             weights=skill.dmp_t.weights + skill.dmp_o.weights).x
    np.testing.assert_allclose(xr, x, rtol=0, atol=1e-12)


def test_learned_motion_follows_the_demonstrations(demos: list[DemoSwitch]) -> None:
    skill = learn_switch_skill(demos, virtual="line")
    for d in demos:
        p = decompose(d, "line", 0.0)
        x = skill.dmp_x.rollout(p.t, x0=p.x[0], g=p.x[-1], tau=d.duration).x
        rms = float(np.sqrt(np.mean(np.sum((x - p.x) ** 2, axis=1))))
        assert rms < 2e-3, (d.name, rms)


@pytest.mark.parametrize("kind", ["arch", "line"])
def test_virtual_motion_goes_from_qa_to_qb(kind: str) -> None:
    disc = Disc(np.array([0.01, 0.15]), 0.0175)
    qa = disc.centre + 0.0175 * np.array([0.0, -1.0])
    qb = disc.centre + 0.0175 * np.array([1.0, 0.0])
    t = np.linspace(0.0, 2.0, 80)
    x = virtual_motion(kind, t, qa, qb, disc, clearance=0.008)
    np.testing.assert_allclose(x[0], qa, atol=1e-15)
    np.testing.assert_allclose(x[-1], qb, atol=1e-15)
    r = np.hypot(*(x - disc.centre).T)
    if kind == "arch":
        assert np.all(r >= disc.radius - 1e-12)
        assert abs(r.max() - (disc.radius + 0.008)) < 2e-4
    else:
        cross = (x - qa) @ np.array([-(qb - qa)[1], (qb - qa)[0]])
        assert np.max(np.abs(cross)) < 1e-15


def test_skill_file_round_trip_and_errors(demos: list[DemoSwitch], tmp_path) -> None:
    skill = learn_switch_skill(demos, virtual="line", tool="finger")
    path = tmp_path / "ss.json"
    skill.save(str(path))
    back = SwitchSkill.load(str(path))
    assert back.virtual == "line" and back.faces == ("upper", "left") and back.n_demos == 5
    for a, b in ((skill.dmp_t, back.dmp_t), (skill.dmp_o, back.dmp_o), (skill.dmp_x, back.dmp_x)):
        np.testing.assert_array_equal(a.weights, b.weights)
    np.testing.assert_array_equal(skill.tool_shift, back.tool_shift)
    data = json.loads(path.read_text())
    data["format"] = "tooltransfer.ss/9"
    path.write_text(json.dumps(data))
    with pytest.raises(SkillFileError, match="version"):
        SwitchSkill.load(str(path))
    data["format"] = "tooltransfer.ss/1"
    data["virtual"] = "spiral"
    path.write_text(json.dumps(data))
    with pytest.raises(SkillFileError, match="virtual"):
        SwitchSkill.load(str(path))
    path.write_text("{not json")
    with pytest.raises(SkillFileError):
        SwitchSkill.load(str(path))


def test_input_validation(demos: list[DemoSwitch]) -> None:
    with pytest.raises(InputError, match="virtual"):
        learn_switch_skill(demos, virtual="spiral")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="demos"):
        learn_switch_skill([])
    d = demos[0]
    with pytest.raises(InputError, match="xy"):
        DemoSwitch(d.t, d.xy[:-1], d.yaw, d.tool_point_from, d.tool_point_to, d.object_point_from,
                   d.object_point_to, d.centre, d.radius)
