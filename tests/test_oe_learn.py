"""Learning the universal OE skill: recovery through the exact inverse of (6), fixed points, round trip."""

from __future__ import annotations

import numpy as np
import pytest

from tooltransfer.planner.learning.oe_skill import DemoPush, condense_recovered, learn_oe_skill, recover
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.problems.fit_cases import minimum_jerk
from tooltransfer.tools import load_tool
from tooltransfer.tools.objects import DiscObject
from tooltransfer.tools.omni.platform import OmniPlatform

START = np.array([0.06, 0.10])
LENGTHS = (0.04, 0.05, 0.045, 0.05)
FACES = ("upper", "left", "upper", "left")


def demo(rng: np.random.Generator, noise: float = 0.0015) -> list[DemoPush]:
    """A staircase pushed by tool 1 on the Omni: forward with the upper face, leftward with the left
    face, each push straight and inside the face's cone at the heading where it starts, lengths
    and durations varied, 30 Hz object track with depth-camera-like noise."""
    tool = load_tool("finger")
    plat = OmniPlatform(a_t=tool.a_t)
    a = START.copy()
    out = []
    for face, length in zip(FACES, LENGTHS, strict=True):
        fr = FaceFrame.build(Setting(tool, plat, DiscObject(0.0175)), face)
        ang = float(fr.push_direction(a)[0]) + rng.uniform(-0.25, 0.25)
        b = a + length * rng.uniform(0.9, 1.1) * np.array([np.cos(ang), np.sin(ang)])
        t = np.arange(0.0, rng.uniform(1.5, 2.5), 1 / 30)
        x = minimum_jerk(a, b, t.size)
        x[0], x[-1] = a, b
        out.append(DemoPush(face, t, x + rng.normal(0, noise, x.shape), fr.heading(x)))
        a = b
    return out


def test_recovery_pins_the_fixed_points() -> None:
    tool = load_tool("finger")
    pushes = demo(np.random.default_rng(0))
    rec = recover(pushes, tool, k=0.5)
    corners = [pushes[0].object_xy[0], *[p.object_xy[-1] for p in pushes]]
    assert np.allclose(rec.fixed, corners)
    assert np.allclose(rec.x[rec.starts], corners, atol=1e-12)
    assert np.all(np.diff(rec.t) > 0)
    assert rec.x.shape == (rec.t.size, 2) and rec.starts[-1] == rec.t.size - 1


def test_fewer_fixed_points_open_the_staircase() -> None:
    """With only the start and end fixed, the forward/left staircase recovers into a motion whose
    corners sit off the demonstration's: each push's direction has opened towards the other's."""
    tool = load_tool("finger")
    pushes = demo(np.random.default_rng(1), noise=0.0)
    rec_all = recover(pushes, tool, k=0.5)
    rec_ends = recover(pushes, tool, k=0.5, fixed=[])
    assert rec_ends.fixed.shape == (2, 2)
    assert np.allclose(rec_ends.x[[0, -1]], rec_all.x[[0, -1]])
    moved = np.linalg.norm(rec_ends.x[rec_all.starts[1:-1]] - rec_all.x[rec_all.starts[1:-1]], axis=1)
    assert moved.max() > 0.005


def test_round_trip_reproduces_the_demonstration() -> None:
    tool = load_tool("finger")
    rng = np.random.default_rng(3)
    pushes = demo(rng, noise=0.0)
    rec = recover(pushes, tool, k=0.5)
    back = condense_recovered(rec, pushes, tool, k=0.5)
    truth = np.vstack([pushes[0].object_xy] + [p.object_xy[1:] for p in pushes[1:]])
    rmse = float(np.sqrt(np.mean(np.sum((back - truth) ** 2, axis=1))))
    # not the identity: pinning spreads each recovered stretch's end mismatch along it, and condensing
    # compresses the shifted directions (measured 1.5 mm on this 19 cm staircase)
    assert rmse < 2e-3


@pytest.mark.parametrize("n_demos", [1, 6])
def test_skill_fitted_on_all_recovered_demonstrations(n_demos: int) -> None:
    tool = load_tool("finger")
    rng = np.random.default_rng(7)
    demos = [demo(rng) for _ in range(n_demos)]
    skill = learn_oe_skill(demos, tool, k=0.5, n_basis=30)
    assert len(skill.recovered) == n_demos
    # every recovered demonstration, rolled out on its own time axis, is close to the skill's motion
    errs = []
    for r in skill.recovered:
        roll = skill.dmp.rollout(r.t, x0=r.x[0], g=r.x[-1], tau=r.t[-1])
        errs.append(float(np.sqrt(np.mean(np.sum((roll.x - r.x) ** 2, axis=1)))))
    length = np.sum(np.linalg.norm(np.diff(skill.recovered[0].x, axis=0), axis=1))
    limit = 0.01 if n_demos == 1 else 0.05  # one demo: a fit; six varied demos: their common shape
    assert max(errs) < limit * length


def test_skill_file_round_trip_and_refusals(tmp_path) -> None:
    from tooltransfer.errors import SkillFileError
    from tooltransfer.planner.learning.oe_skill import OESkill

    skill = learn_oe_skill([demo(np.random.default_rng(5))], load_tool("finger"), k=0.5, n_basis=20)
    path = skill.save(tmp_path / "oe.json")
    back = OESkill.load(path)
    t = np.linspace(0, skill.dmp.tau, 50)
    assert np.allclose(back.dmp.rollout(t, x0=START, g=START + 0.1).x, skill.dmp.rollout(t, x0=START, g=START + 0.1).x)
    assert back.k == 0.5 and back.tool == "finger" and np.array_equal(back.recovered[0].x, skill.recovered[0].x)
    bad = tmp_path / "bad.json"
    bad.write_text(path.read_text().replace("tooltransfer.oe/1", "tooltransfer.oe/9"))
    with pytest.raises(SkillFileError, match=r"tooltransfer\.oe/1"):
        OESkill.load(bad)
    bad.write_text(path.read_text()[:100])
    with pytest.raises(SkillFileError, match="not valid JSON"):
        OESkill.load(bad)
