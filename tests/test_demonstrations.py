"""Demonstrations: the scripted operator on the simulated Omni, the dataset format and its loader,
the committed default dataset, and segmentation against the operator's ground truth."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from planner.segmentation import segment
from problems.dataset import DatasetError, load_dataset
from tools import load_tool
from tools.omni.reach import reach_sector
from tools.operator import DEMO_SCENE
from tools.operator.generate import generate_demonstrations

DATA = Path(__file__).resolve().parents[1] / "problems" / "data" / "finger_demos"


@pytest.fixture(scope="module")
def fresh(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The default dataset generated again (8 demonstrations, seed 0)."""
    return generate_demonstrations(tmp_path_factory.mktemp("demos") / "finger_demos", n=8, seed=0)


def test_regenerating_reproduces_the_committed_dataset(fresh: Path) -> None:
    for name in ["meta.yaml", "truth.yaml", *sorted(p.name for p in DATA.glob("*.csv"))]:
        assert (fresh / name).read_text() == (DATA / name).read_text(), name


def test_every_demonstration_reaches_the_target_square() -> None:
    ds = load_dataset(DATA)
    assert len(ds.demonstrations) == 8
    for d in ds.demonstrations:
        assert ds.truth[d.name]["reached_target"]
        assert DEMO_SCENE.in_target(np.array(ds.truth[d.name]["final_object_xy"]))
        assert 25.0 < d.t_object.size / d.t_object[-1] < 35.0  # a camera at about 30 Hz
        assert d.t_tool.size / d.t_tool[-1] >= 99.0  # encoders at 100 Hz or more


def test_scene_corners_are_inside_the_reach() -> None:
    sec = reach_sector(__import__("tools.omni.platform", fromlist=["OmniPlatform"]).OmniPlatform())
    r = np.linalg.norm(DEMO_SCENE.corners - sec.centre, axis=1)
    assert np.all((r > sec.r_in) & (r < sec.r_out))


def _match(found, truth):
    used, errs, missed = set(), [], 0
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
    return np.abs(np.array(errs)), missed, len(found) - len(used)


def test_segmentation_finds_every_switch_and_nearly_every_push() -> None:
    ds = load_dataset(DATA)
    tool = load_tool("finger")
    for d in ds.demonstrations:
        seg = segment(d, tool)
        truth = ds.truth[d.name]
        errs, missed, _ = _match(seg.pushes, truth["pushes"])
        assert missed <= 0.1 * len(truth["pushes"]), d.name  # measured: at most 1 of 14-16 missed
        assert np.median(errs) < 0.15  # [s] (the 50 ms target: see the xfail below)
        assert [(s.face_from, s.face_to) for s in seg.switches] == [(s["from"], s["to"]) for s in truth["switches"]]
        assert len(seg.fixed_points) == len(truth["switches"])


@pytest.mark.xfail(strict=True, reason="not met yet: every push found, within 50 ms, no spurious ones (measured on "
                   "the default dataset: 3 of 115 pushes missed, 21 spurious short contacts, median error 0.05 s "
                   "at the start and 0.10 s at the end, 7% of pushes within 50 ms)")
def test_segmentation_meets_the_timing_target() -> None:
    ds = load_dataset(DATA)
    tool = load_tool("finger")
    for d in ds.demonstrations:
        errs, missed, spurious = _match(segment(d, tool).pushes, ds.truth[d.name]["pushes"])
        assert missed == 0 and spurious == 0 and errs.max() <= 0.05


@pytest.mark.parametrize(
    ("edit", "where", "words"),
    [
        (lambda s: s.replace("t,obj_x", "time,obj_x", 1), "row 1", "missing t"),
        (lambda s: "\n".join([*s.splitlines()[:2], "nan" + s.splitlines()[2][8:], *s.splitlines()[3:]]),
         "row 3, column t", "finite"),
        (lambda s: "\n".join(s.splitlines()[:6]) + "\n", "columns", "at least 10"),
    ],
)
def test_loader_names_file_row_and_column(tmp_path: Path, edit, where: str, words: str) -> None:
    folder = tmp_path / "ds"
    folder.mkdir()
    (folder / "meta.yaml").write_text((DATA / "meta.yaml").read_text())
    for p in DATA.glob("*.csv"):
        (folder / p.name).write_text(p.read_text())
    target = folder / "demo_00.csv"
    target.write_text(edit(target.read_text()))
    with pytest.raises(DatasetError) as err:
        load_dataset(folder)
    assert str(target) in str(err.value) and where in str(err.value) and words in str(err.value)


def test_loader_rejects_time_going_back_and_unknown_tool(tmp_path: Path) -> None:
    folder = tmp_path / "ds"
    folder.mkdir()
    meta = (DATA / "meta.yaml").read_text()
    (folder / "meta.yaml").write_text(meta.replace("tool: finger", "tool: hammer"))
    with pytest.raises(DatasetError, match="tool"):
        load_dataset(folder)
    (folder / "meta.yaml").write_text(meta)
    for p in DATA.glob("*.csv"):
        (folder / p.name).write_text(p.read_text())
    lines = (folder / "demo_01.csv").read_text().splitlines()
    lines[40], lines[41] = lines[41], lines[40]
    (folder / "demo_01.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(DatasetError, match=r"row 4[12], column t: expected .* times increasing"):
        load_dataset(folder)
