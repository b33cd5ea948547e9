"""Segmentation against the scripted operator's ground truth, on the committed default dataset
(which tests/test_operator.py regenerates), plus a synthetic push with known contact times."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.apps.operator.generate import generate_demonstrations
from tooltransfer.planner.learning.segmentation import Segmentation, segment
from tooltransfer.planner.learning.segmentation.rest import camera_noise, still_tail
from tooltransfer.problems.dataset import Dataset, Demonstration, load_dataset
from tooltransfer.tools import load_tool
from tooltransfer.tools.objects import OBJECT_RADIUS

DATA = Path(__file__).resolve().parents[1] / "problems" / "data" / "finger_demos"
TIMING = 0.05
"""Largest contact timing error allowed [s] (the issue's target)."""


@pytest.fixture(scope="module")
def ds() -> Dataset:
    return load_dataset(DATA)


@pytest.fixture(scope="module")
def segs(ds: Dataset) -> list[Segmentation]:
    tool = ds.tool()
    return [segment(d, tool) for d in ds.demonstrations]


def _match(found, truth: list[dict]) -> tuple[list[tuple[float, float]], int, int]:
    """One-to-one matching of found pushes to true ones (same face, largest overlap): the timing
    errors (start, end) [s], the number of true pushes missed and of found pushes left over."""
    used: set[int] = set()
    errs, missed = [], 0
    for tp in truth:
        cands = [(min(f.t_end, tp["t_end"]) - max(f.t_start, tp["t_start"]), i) for i, f in enumerate(found)
                 if f.face == tp["face"] and i not in used]
        cands = [c for c in cands if c[0] > 0]
        if not cands:
            missed += 1
            continue
        i = max(cands)[1]
        used.add(i)
        errs.append((found[i].t_start - tp["t_start"], found[i].t_end - tp["t_end"]))
    return errs, missed, len(found) - len(used)


def _all_errors(ds: Dataset, segs: list[Segmentation]) -> np.ndarray:
    all_errs = []
    for d, s in zip(ds.demonstrations, segs, strict=True):
        errs, missed, spurious = _match(s.pushes, ds.truth[d.name]["pushes"])
        assert missed == 0 and spurious == 0, (d.name, missed, spurious)
        all_errs += errs
    return np.abs(np.array(all_errs))


def test_every_push_found_and_none_spurious(ds: Dataset, segs: list[Segmentation]) -> None:
    e = _all_errors(ds, segs)
    assert len(e) >= 8 * 12
    assert np.median(e) <= 0.01  # [s]
    assert np.mean(e.max(axis=1) <= TIMING) >= 0.99


def test_every_push_within_50_ms(ds: Dataset, segs: list[Segmentation]) -> None:
    """Measured: starts within 30 ms, ends within 17 ms (medians 1.3 ms and 2.4 ms)."""
    e = _all_errors(ds, segs)
    assert e.max() <= TIMING, f"largest timing error {e.max():.3f} s"


@pytest.fixture(scope="module")
def fresh(tmp_path_factory: pytest.TempPathFactory) -> Dataset:
    """Four demonstrations of another seed (about 1 s each to generate)."""
    return load_dataset(generate_demonstrations(tmp_path_factory.mktemp("seed1") / "demos", n=4, seed=1))


def test_a_dataset_of_another_seed(fresh: Dataset) -> None:
    """Not tuned to the committed dataset: every push and switch of fresh demonstrations found,
    none spurious, every push boundary within 50 ms (one push of these lingers 66 ms at its
    farthest advance, the contact ending at the end of that stall)."""
    tool = fresh.tool()
    for d in fresh.demonstrations:
        s = segment(d, tool)
        truth = fresh.truth[d.name]
        errs, missed, spurious = _match(s.pushes, truth["pushes"])
        assert missed == 0 and spurious == 0, (d.name, missed, spurious)
        assert np.abs(errs).max() <= TIMING, (d.name, np.abs(errs).max())
        assert [(w.face_from, w.face_to) for w in s.switches] == [(w["from"], w["to"]) for w in truth["switches"]]


def test_a_still_object_is_not_cut_and_a_move_is_found() -> None:
    """The rest's change-point test: 300 still stretches of 150 camera samples (1.5 mm noise) are
    never cut (at most 1e-4 each), and a 3 mm move after 100 of them is always found, mostly at
    the move and at worst 8 samples (0.27 s) off."""
    rng = np.random.default_rng(3)
    idx = np.arange(150)
    for _ in range(300):
        xy = rng.normal(0.0, 0.0015, (150, 2))
        kept, whole = still_tail(xy, idx, camera_noise(xy))
        assert whole and kept.size == 150
    cuts = []
    for _ in range(50):
        xy = rng.normal(0.0, 0.0015, (150, 2))
        xy[100:] += [0.003, 0.0]
        kept, whole = still_tail(xy, idx, camera_noise(xy))
        assert not whole
        cuts.append(kept[0])
    assert np.median(cuts) == 100 and np.abs(np.array(cuts) - 100).max() <= 8


def test_every_switch_found_in_order_and_none_spurious(ds: Dataset, segs: list[Segmentation]) -> None:
    for d, s in zip(ds.demonstrations, segs, strict=True):
        truth = ds.truth[d.name]["switches"]
        assert [(w.face_from, w.face_to) for w in s.switches] == [(w["from"], w["to"]) for w in truth], d.name
        for w, tw in zip(s.switches, truth, strict=True):  # the switching move lies between the two pushes
            assert w.t_start <= tw["t_start"] + TIMING and tw["t_end"] <= w.t_end + TIMING


def test_fixed_points_are_the_corners(ds: Dataset, segs: list[Segmentation]) -> None:
    for d, s in zip(ds.demonstrations, segs, strict=True):
        corners = np.array([w["object_xy"] for w in ds.truth[d.name]["switches"]])
        assert s.fixed_points.shape == corners.shape
        assert np.linalg.norm(s.fixed_points - corners, axis=1).max() < 0.001  # [m]; camera noise 1.5 mm


def test_switch_contact_points_lie_on_the_faces_and_the_object(ds: Dataset, segs: list[Segmentation]) -> None:
    tool = ds.tool()
    for s in segs:
        for w, c in zip(s.switches, s.fixed_points, strict=True):
            for face, p in ((w.face_from, w.tool_point_from), (w.face_to, w.tool_point_to)):
                a, b = tool.face(face).contact_segment()
                u = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
                assert np.hypot(*(p - (a + u * (b - a)))) <= 0.002  # the segmentation's face_tol
            for q in (w.object_point_from, w.object_point_to):
                assert np.hypot(*(q - c)) == pytest.approx(OBJECT_RADIUS, abs=0.001)


def test_labels_are_the_pushes(ds: Dataset, segs: list[Segmentation]) -> None:
    for d, s in zip(ds.demonstrations, segs, strict=True):
        assert len(s.labels) == d.t_tool.size
        inside = np.zeros(d.t_tool.size, dtype=bool)
        for p in s.pushes:
            assert all(s.labels[k] == p.face for k in p.samples)
            inside[p.samples] = True
        assert all(lab is None for lab, k in zip(s.labels, inside, strict=True) if not k)


def test_manual_override_of_the_fixed_points(ds: Dataset) -> None:
    tool = ds.tool()
    d = ds.demonstrations[0]
    s = segment(d, tool, fixed_points=[[0.05, 0.16]])
    np.testing.assert_array_equal(s.fixed_points, [[0.05, 0.16]])
    with pytest.raises(InputError, match="fixed_points"):
        segment(d, tool, fixed_points=[0.05, 0.16, 0.2])


def test_a_noisier_camera_still_gives_every_push_and_switch(ds: Dataset) -> None:
    """2 mm instead of 1.5 mm camera noise (the top of the issue's range)."""
    tool = ds.tool()
    rng = np.random.default_rng(7)
    extra = np.sqrt(0.002**2 - 0.0015**2)
    for d in ds.demonstrations:
        noisy = replace(d, object_xy=d.object_xy + rng.normal(0.0, extra, d.object_xy.shape))
        s = segment(noisy, tool)
        errs, missed, spurious = _match(s.pushes, ds.truth[d.name]["pushes"])
        assert missed == 0 and spurious == 0
        assert np.abs(errs).max() <= TIMING
        assert len(s.switches) == len(ds.truth[d.name]["switches"])


def _synthetic(seed: int, retouch: bool = False) -> tuple[Demonstration, float, float]:
    """One forward push with the upper face (heading 0), no simulator: the tool rests, pushes 20 mm
    (minimum jerk, 1.5 s) and eases off 3 mm in an overlapping movement; the puck starts 3 mm in
    front of the face and moves with it while touching. With ``retouch`` the hand falls back
    0.1 mm at the end of the push and comes forward 0.2 mm before easing off, touching the puck
    again for 27 ms 0.14 s later (the ground truth's rules make that one push, ending at the second
    touch). Returns the recording (camera 30 Hz with 1.5 mm noise, encoders 100 Hz) and the true
    contact start and end [s]."""
    rng = np.random.default_rng(seed)

    def mj(u: np.ndarray) -> np.ndarray:
        u = np.clip(u, 0.0, 1.0)
        return u**3 * (10 - 15 * u + 6 * u**2)

    def tool_y(t: np.ndarray) -> np.ndarray:
        if retouch:
            return (0.02 * mj((t - 1.5) / 1.5) - 0.0001 * mj((t - 2.95) / 0.1) + 0.0002 * mj((t - 3.05) / 0.1)
                    - 0.003 * mj((t - 3.1) / 0.3))
        return 0.02 * mj((t - 1.5) / 1.5) - 0.003 * mj((t - 2.8) / 0.3)

    fine = np.arange(0.0, 5.0, 1e-4)
    y = tool_y(fine)
    reach = 0.006 + OBJECT_RADIUS  # face line (y = 6 mm in the tool frame) plus the radius
    puck = np.maximum(0.003 + reach, np.maximum.accumulate(y) + reach)
    t_start = float(fine[np.argmax(y >= 0.003)])
    t_end = float(fine[np.argmax(y)])
    t_t = np.arange(0.01, 5.0, 0.01)
    t_o = np.arange(0.033, 5.0, 1 / 30)
    pose = np.column_stack([np.zeros_like(t_t), tool_y(t_t), np.zeros_like(t_t)])
    obj = np.column_stack([np.zeros_like(t_o), np.interp(t_o, fine, puck)]) + rng.normal(0, 0.0015, (t_o.size, 2))
    return Demonstration("synthetic", t_o, obj, t_t, pose, np.zeros((t_t.size, 3))), t_start, t_end


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_synthetic_push_with_known_contact_times(seed: int) -> None:
    demo, t_start, t_end = _synthetic(seed)
    s = segment(demo, load_tool("finger"))
    assert [p.face for p in s.pushes] == ["upper"] and not s.switches
    assert abs(s.pushes[0].t_start - t_start) <= 0.02
    assert abs(s.pushes[0].t_end - t_end) <= 0.02
    assert s.pushes[0].object_after[1] - s.pushes[0].object_before[1] == pytest.approx(0.017, abs=0.001)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_touch_just_after_a_push_belongs_to_it(seed: int) -> None:
    """Contacts of one face less than merge_gap apart are merged before short ones are dropped, as
    in the ground truth (dropping first ended this push 154 ms early, at the first touch's end)."""
    demo, t_start, t_end = _synthetic(seed, retouch=True)
    s = segment(demo, load_tool("finger"))
    assert [p.face for p in s.pushes] == ["upper"]
    assert abs(s.pushes[0].t_start - t_start) <= 0.02
    assert abs(s.pushes[0].t_end - t_end) <= 0.02


def test_segment_command_prints_and_draws(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fig = tmp_path / "demos.png"
    assert main(["segment", str(DATA), "--figure", str(fig)]) == 0
    out = capsys.readouterr().out
    assert out.count("3 switches (upper->left, left->upper, upper->left)") == 8
    assert fig.stat().st_size > 10_000
    override = tmp_path / "fixed.json"
    override.write_text(json.dumps({"demo_00": [[0.06, 0.16]]}))
    assert main(["segment", str(DATA), "--fixed-points", str(override)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("demo_00") and lines[0].endswith("fixed points [m]: (0.0600, 0.1600)")
    assert not lines[1].endswith("fixed points [m]: (0.0600, 0.1600)")
    override.write_text("[1, 2")
    assert main(["segment", str(DATA), "--fixed-points", str(override)]) == 2
    assert "--fixed-points" in capsys.readouterr().err
    assert main(["segment", str(tmp_path / "nowhere")]) == 2
