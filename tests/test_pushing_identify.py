"""Identifying the push mechanics (mu, c) from recorded pushes (tooltransfer.tools.pushing.identify,
tooltransfer.planner.learning.identify).

* Synthetic recordings made by the forward model itself (known mu, c; camera noise 1.5 mm at
  30 Hz): the fit recovers them within a few standard deviations, and the deviations shrink
  with more pushes as 1 / sqrt(n); pushes along the normal only leave c (and mu) unexcited, which
  is flagged with a large deviation and a message, not an error.
* A calibration recording of the MuJoCo platform (``tooltransfer demos --calibration``): the
  identified model predicts every recorded push's end position within 1 mm (median about 0.25 mm,
  the issue's target is 1 mm median) and gives plausible values (the platform's tool friction is
  0.8, its straight pushes behave like c = 0.59).
* The skills file carries the identified mechanics, and a file written before it did still loads.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, example, given, settings
from hypothesis import strategies as st

from tooltransfer.errors import InputError, SkillFileError
from tooltransfer.planner.apps.cli import main
from tooltransfer.problems.dataset import load_dataset
from tooltransfer.tools.library import load_tool
from tooltransfer.tools.objects import OBJECT_RADIUS
from tooltransfer.tools.pushing.forward import simulate
from tooltransfer.tools.pushing.identify import Identification, RecordedPush, identify_mechanics, rest_position
from tooltransfer.tools.pushing.mechanics import PushMechanics

DATA = Path(__file__).resolve().parents[1] / "problems" / "data" / "finger_demos"
TOOL = load_tool("finger")
NOISE = 0.0015
"""Camera noise [m] per axis, as the generated recordings."""
ANGLES = (0, 15, -15, 30, -30, 45, -45, 80, -80)
"""Synthetic pushes' angles [deg] off the left face's normal (80 degrees slides for these mu, c)."""


def synthetic_pushes(mech: PushMechanics, n: int, seed: int, angles: tuple[float, ...] = ANGLES) -> list[RecordedPush]:
    """``n`` straight pushes of the finger's left face at ``angles`` off its normal (cycled), made by
    the forward model with ``mech``: tool poses at 100 Hz for 1.2 s (a minimum-jerk stroke from 2 mm
    behind the puck, at most 15 mm, keeping the contact on the face), the camera at 30 Hz for 1.5 s
    with 1.5 mm noise; the rest positions exact before (the model's own start) and from 20 noisy
    frames after."""
    rng = np.random.default_rng(seed)
    face = TOOL.face("left")
    ahead = float((face.end - face.start) @ np.array([-face.normal[1], face.normal[0]]))
    out = []
    for i in range(n):
        a = np.radians(angles[i % len(angles)])
        yaw = rng.normal(0.0, 0.2)
        rot = np.array([[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]])
        normal = rot @ face.normal
        d = np.cos(a) * normal + np.sin(a) * np.array([-normal[1], normal[0]])
        s = 0.5 if a == 0 else (0.95 if (a > 0) == (ahead > 0) else 0.05)  # the contact rolls into the face
        obj = np.array([0.0, 0.15]) + rng.normal(0.0, 0.01, 2)
        origin = obj - OBJECT_RADIUS * normal - rot @ face.point(s)
        length = min(0.015, 0.0085 / max(abs(np.sin(a)), 1e-9))
        u = np.linspace(0.0, 1.0, 121)
        travel = -0.002 + u**3 * (10 - 15 * u + 6 * u**2) * (length + 0.002)
        poses = np.column_stack([origin + travel[:, None] * d, np.full(u.size, yaw)])
        t_tool = 1.2 * u
        trace = simulate(TOOL, poses, obj, OBJECT_RADIUS, mech)
        t_cam = np.arange(0.0, 1.5, 1.0 / 30.0)
        seen = np.column_stack([np.interp(t_cam, t_tool, trace.object_xy[:, j]) for j in range(2)])
        seen += rng.normal(0.0, NOISE, seen.shape)
        end = trace.final + rng.normal(0.0, NOISE / np.sqrt(20), 2)
        out.append(RecordedPush(t_tool, poses, t_cam, seen, obj, end, f"synthetic#{i}"))
    return out


@settings(max_examples=4, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow])
@given(mu=st.floats(0.35, 0.9), c=st.floats(0.55, 0.9))
@example(mu=0.8, c=0.59)
def test_synthetic_pushes_give_back_mu_and_c(mu: float, c: float) -> None:
    """Over this range mu (1 + 1/c^2) <= 3.9, so the 80 degree pushes (tan 80 = 5.7) slide."""
    truth = PushMechanics(mu, c)
    ident = identify_mechanics(TOOL, OBJECT_RADIUS, synthetic_pushes(truth, 27, seed=1))
    m = ident.mechanics
    assert ident.mu_excited and ident.c_excited and ident.message == ""
    assert m.source == "identified" and ident.n_pushes == 27 and ident.n_samples == 27 * 45
    assert abs(m.mu - mu) < 4 * m.mu_std, (m.mu, m.mu_std, mu)
    assert abs(m.c - c) < 4 * m.c_std, (m.c, m.c_std, c)
    assert m.mu_std < 0.25 * mu and m.c_std < 0.1 * c
    assert ident.sigma == pytest.approx(NOISE, rel=0.1)  # the residuals are the camera's noise
    assert np.median(ident.end_error) < 0.7e-3  # the recorded end's own noise: 0.39 mm median


@pytest.mark.serial  # the identification's wall time is bounded
def test_the_uncertainty_shrinks_with_more_pushes() -> None:
    truth = PushMechanics(0.6, 0.7)
    few = identify_mechanics(TOOL, OBJECT_RADIUS, synthetic_pushes(truth, 18, seed=2))
    many = identify_mechanics(TOOL, OBJECT_RADIUS, synthetic_pushes(truth, 72, seed=3))
    for name in ("mu", "c"):  # 4 times the pushes: half the deviation (1 / sqrt(n))
        ratio = getattr(many.mechanics, f"{name}_std") / getattr(few.mechanics, f"{name}_std")
        assert 0.3 < ratio < 0.7, (name, ratio)
        assert abs(getattr(many.mechanics, name) - getattr(truth, name)) < 4 * getattr(many.mechanics, f"{name}_std")
    assert many.wall_time < 5.0  # 72 pushes at once


def test_pushes_along_the_normal_leave_c_unexcited() -> None:
    """Along the normal the puck goes straight whatever c is (and the contact sticks, so mu does not
    act either): both are flagged with a large deviation and a message, and keep their initial values."""
    ident = identify_mechanics(TOOL, OBJECT_RADIUS, synthetic_pushes(PushMechanics(0.6, 0.8), 12, 4, angles=(0,)))
    m = ident.mechanics
    assert not ident.c_excited and not ident.mu_excited
    assert "c is not excited" in ident.message and "mu is not excited" in ident.message
    assert "--calibration" in ident.message
    assert m.c_std > 0.3 and m.mu_std > 0.3  # the prior's spread: a factor e
    assert (m.mu, m.c) == (0.8, 0.59)
    assert np.median(ident.end_error) < 0.7e-3  # the model still predicts these pushes


def test_bad_inputs_name_the_field() -> None:
    push = synthetic_pushes(PushMechanics(), 1, 5)[0]
    with pytest.raises(InputError, match="pushes"):
        identify_mechanics(TOOL, OBJECT_RADIUS, [])
    with pytest.raises(InputError, match=r"pushes\[1\]"):
        identify_mechanics(TOOL, OBJECT_RADIUS, [push, "push"])  # type: ignore[list-item]
    with pytest.raises(InputError, match=r"initial\.c"):
        identify_mechanics(TOOL, OBJECT_RADIUS, [push], initial=PushMechanics(0.8, 1.8))
    with pytest.raises(InputError, match="radius"):
        identify_mechanics(TOOL, -1.0, [push])
    with pytest.raises(InputError, match=r"p7\.tool_pose"):
        RecordedPush(push.t_tool, push.tool_pose[:, :2], push.t_object, push.object_xy, push.object_start,
                     push.object_end, "p7")
    with pytest.raises(InputError, match=r"p7\.t_object"):
        RecordedPush(push.t_tool, push.tool_pose, push.t_object[::-1], push.object_xy, push.object_start,
                     push.object_end, "p7")
    with pytest.raises(InputError, match="rest"):
        rest_position(push.t_object, push.object_xy, 5.0, 6.0)
    assert rest_position(push.t_object, push.object_xy, 0.0, 0.2) == pytest.approx(
        push.object_xy[:7].mean(axis=0))


# ------------------------------------------------------------------ the MuJoCo platform


@pytest.fixture(scope="module")
def calibration(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A calibration recording through the CLI (16 trials, 77 strokes; about 5 s)."""
    out = tmp_path_factory.mktemp("calibration") / "cal"
    assert main(["demos", "--calibration", "--out", str(out), "--seed", "0"]) == 0
    return out


def test_the_calibration_recording_is_a_dataset_of_straight_pushes(calibration: Path) -> None:
    ds = load_dataset(calibration)
    assert ds.meta.scene["kind"] == "calibration" and ds.meta.generator["program"] == "tooltransfer demos --calibration"
    names = [d.name for d in ds.demonstrations]
    assert len(names) == 16 and {"upper_p00", "left_m45", "left_p80", "left_m80"} <= set(names)
    for d in ds.demonstrations:
        truth = ds.truth[d.name]
        moved = np.hypot(*np.subtract(truth["final_object_xy"], truth["object_start"]))
        assert 0.015 <= moved <= 0.03, (d.name, moved)  # each trial moves the puck 15-30 mm
        assert len(truth["pushes"]) >= 2 and all(p["face"] == truth["face"] for p in truth["pushes"])
        assert all(p["t_end"] - p["t_start"] > 0.05 for p in truth["pushes"])
        tool = ds.tool().face(truth["face"])
        lateral = max(p["length"] for p in truth["pushes"]) * abs(np.sin(np.radians(truth["angle_deg"])))
        assert lateral <= tool.length  # the tool's sideways travel (>= the contact's) fits on the face


@pytest.mark.serial  # the identification's wall time is bounded
def test_the_identified_model_predicts_the_platforms_pushes(calibration: Path) -> None:
    from tooltransfer.planner.learning.identify import identify_dataset

    ident = identify_dataset(calibration)
    m = ident.mechanics
    assert ident.mu_excited and ident.c_excited
    assert ident.n_pushes >= 70  # the segmentation finds (nearly) every stroke
    assert np.median(ident.end_error) < 1e-3  # the target; measured 0.26 mm
    assert np.percentile(ident.end_error, 90) < 1e-3  # measured 0.59 mm
    assert 0.45 < m.mu < 1.0 and m.mu_std < 0.15  # measured 0.58 +- 0.09 (MuJoCo slides below its 0.8)
    assert 0.5 < m.c < 0.7 and m.c_std < 0.06  # measured 0.58 +- 0.04
    assert ident.wall_time < 5.0
    again = Identification.from_dict(json.loads(json.dumps(ident.to_dict(), allow_nan=False)))
    assert again.mechanics == m and again.summary() == ident.summary()


# ------------------------------------------------------------------ the skills file


def test_skills_files_carry_the_mechanics_and_old_files_load(tmp_path: Path, calibration: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    from tooltransfer.planner.learning.skills import Skills, learn_skills

    out = tmp_path / "skills.json"
    assert main(["learn", str(DATA), "--calibration", str(calibration), "-o", str(out)]) == 0
    assert "push mechanics from" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert doc["mechanics"]["source"] == "identified" and doc["identification"]["kind"] == "calibration"
    skills = Skills.load(out)
    assert skills.mechanics == PushMechanics.from_dict(doc["mechanics"])
    assert skills.identification["dataset"] == str(calibration)
    again = Skills.load(skills.save(tmp_path / "again.json"))  # round trip
    assert again.mechanics == skills.mechanics and again.to_dict() == skills.to_dict()
    own = learn_skills(DATA)  # from the demonstrations' own pushes: c identified, mu not excited
    assert own.mechanics is not None and own.identification["kind"] == "demonstrations"
    assert 0.5 < own.mechanics.c < 0.65 and not own.identification["mu_excited"]
    assert learn_skills(DATA, with_ss=False, with_mechanics=False).mechanics is None
    old = {k: v for k, v in doc.items() if k not in ("mechanics", "identification")}  # written before
    (tmp_path / "old.json").write_text(json.dumps(old))
    before = Skills.load(tmp_path / "old.json")
    assert before.mechanics is None and before.identification is None
    assert before.to_dict() == old
    bad = {**doc, "mechanics": {"mu": -1.0, "c": 0.6}}
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(SkillFileError, match=r"mechanics\.mu"):
        Skills.load(tmp_path / "bad.json")
    assert main(["learn", str(DATA), "--calibration", str(tmp_path / "nowhere"), "-o", str(out)]) == 2
    assert "calibration" in capsys.readouterr().err
