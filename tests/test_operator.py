"""The scripted operator and the generated demonstrations: regeneration reproduces the committed
default dataset, every demonstration reaches the target square, the scene and every executed
tool path lie inside the Omni's reach, the tool keeps clear of the obstacle, sensor-like records.

The default dataset is generated once for the module (8 demonstrations, about 12 s), and once more
with other BLAS kernels. The contact simulation is chaotic: the last bits of one BLAS call move a
later push by a sample and a demonstration's final puck position by a tenth of a millimetre. The
committed dataset was written with OpenBLAS's SkylakeX (AVX-512) kernels and NumPy's AVX-512 loops,
and reproduces bit for bit only with those (``OPENBLAS_CORETYPE=SkylakeX`` on a CPU that has
AVX-512; the library otherwise picks the kernels of its CPU, e.g. Haswell's on an AMD EPYC); with
other kernels the same demonstrations come out: every one reaches the target with the same pushes
and switches, face by face.
"""

from __future__ import annotations

import itertools
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from tooltransfer.errors import InputError
from tooltransfer.planner.apps.cli import main
from tooltransfer.planner.apps.operator.generate import JOINT_STEP, generate_demonstrations
from tooltransfer.planner.apps.operator.operator import MIN_CONTACT
from tooltransfer.planner.learning.segmentation.geometry import nearest_on_segments, to_tool_frame
from tooltransfer.problems.dataset import Dataset, load_dataset
from tooltransfer.problems.demo_scene import DEMO_SCENE
from tooltransfer.tools.omni.ik import joint_path, table_pose
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.omni.reach import reach_sector

DATA = Path(__file__).resolve().parents[1] / "problems" / "data" / "finger_demos"
CSV_TOLERANCE = 1e-6
"""Regenerated CSV values may differ from the committed ones by one unit of the 6th decimal: the
simulation and numpy are bit-exact on one machine, but other CPUs or library builds can change the
last bits of a float, and a value next to a rounding boundary then prints one unit differently."""


#: The OpenBLAS kernels the committed dataset was written with, and the CPU flags they (and NumPy's
#: AVX-512 loops) need.
GENERATED_WITH_CORE = "SkylakeX"
CORE_FLAGS = {"avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl"}
#: Kernels of another family, for the check that the demonstrations survive other last bits.
OTHER_CORE = {"x86_64": "Haswell", "AMD64": "Haswell", "aarch64": "ARMV8"}


def _cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    return next((set(line.split(":", 1)[1].split()) for line in text.splitlines() if line.startswith("flags")),
                set())


def _generate(out: Path, core: str | None) -> tuple[Path, float]:
    """The default dataset (the command's defaults) generated in a new process with OpenBLAS's kernels
    ``core`` (None: the ones it picks for this CPU), and the wall time the generation took [s]."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    env.pop("OPENBLAS_CORETYPE", None)
    if core is not None:
        env["OPENBLAS_CORETYPE"] = core
    code = ("import sys, time\n"
            "from pathlib import Path\n"
            "from tooltransfer.planner.apps.operator.generate import generate_demonstrations\n"
            "t0 = time.perf_counter()\n"
            "generate_demonstrations(Path(sys.argv[1]), n=8, seed=0)\n"
            "print(time.perf_counter() - t0)\n")
    done = subprocess.run([sys.executable, "-c", code, str(out)], env=env, capture_output=True, text=True,
                          check=False)
    assert done.returncode == 0, done.stderr
    return out, float(done.stdout.split()[-1])


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """The default dataset generated again with the kernels it was written with (skipped on a CPU
    that cannot run them) and the wall time it took [s]."""
    if platform.machine() not in ("x86_64", "AMD64") or not CORE_FLAGS <= _cpu_flags():
        pytest.skip(f"the committed dataset is bit-reproducible with OpenBLAS's {GENERATED_WITH_CORE} "
                    f"(AVX-512) kernels, which this CPU cannot run")
    return _generate(tmp_path_factory.mktemp("demos") / "finger_demos", GENERATED_WITH_CORE)


@pytest.fixture(scope="module")
def regenerated_other(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The default dataset generated with kernels of another family than it was written with."""
    core = OTHER_CORE.get(platform.machine())
    if core == "Haswell" and not {"avx2", "fma"} <= _cpu_flags():
        core = None  # a CPU too old for Haswell's kernels: its own are older still
    return _generate(tmp_path_factory.mktemp("demos_other") / "finger_demos", core)[0]


@pytest.fixture(scope="module")
def ds() -> Dataset:
    return load_dataset(DATA)


def _csv_values(path: Path) -> tuple[list[str], np.ndarray, np.ndarray]:
    lines = path.read_text().splitlines()
    cells = [line.split(",") for line in lines[1:]]
    empty = np.array([[c == "" for c in row] for row in cells])
    values = np.array([[float(c) if c else 0.0 for c in row] for row in cells])
    return lines[:1], empty, values


@pytest.mark.serial  # the generation's wall time is bounded
def test_regenerating_reproduces_the_committed_dataset(regenerated: tuple[Path, float]) -> None:
    fresh, wall = regenerated
    assert wall < 60.0
    for name in ("meta.yaml", "truth.yaml"):
        assert yaml.safe_load((fresh / name).read_text()) == yaml.safe_load((DATA / name).read_text()), name
    names = sorted(p.name for p in DATA.glob("*.csv"))
    assert names == sorted(p.name for p in fresh.glob("*.csv")) and len(names) == 8
    for name in names:
        h0, e0, v0 = _csv_values(DATA / name)
        h1, e1, v1 = _csv_values(fresh / name)
        assert h0 == h1 and e0.shape == e1.shape, name
        assert np.array_equal(e0, e1), name  # the same samples of each stream
        assert np.abs(v0 - v1).max() <= CSV_TOLERANCE, name


def test_other_last_bits_give_the_same_demonstrations(regenerated_other: Path) -> None:
    assert yaml.safe_load((regenerated_other / "meta.yaml").read_text()) == yaml.safe_load(
        (DATA / "meta.yaml").read_text())
    fresh = yaml.safe_load((regenerated_other / "truth.yaml").read_text())
    committed = yaml.safe_load((DATA / "truth.yaml").read_text())
    assert fresh.keys() == committed.keys()
    demos = [k for k in committed if k.startswith("demo_")]
    assert len(demos) == 8
    for k in demos:
        assert fresh[k]["reached_target"] and committed[k]["reached_target"], k
        assert [p["face"] for p in fresh[k]["pushes"]] == [p["face"] for p in committed[k]["pushes"]], k
        assert [(w["from"], w["to"]) for w in fresh[k]["switches"]] == [
            (w["from"], w["to"]) for w in committed[k]["switches"]], k


def test_another_seed_gives_other_demonstrations(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demos", "--n", "1", "--seed", "1", "--out", str(tmp_path / "s1")]) == 0
    assert "wrote 1 demonstrations" in capsys.readouterr().out
    other = load_dataset(tmp_path / "s1").demonstrations[0]
    first = load_dataset(DATA).demonstrations[0]
    assert other.t_tool.size != first.t_tool.size or not np.allclose(other.tool_pose, first.tool_pose)


def test_bad_arguments_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(InputError, match="tool"):
        generate_demonstrations(tmp_path, n=1, tool="slope")
    with pytest.raises(InputError, match="n"):
        generate_demonstrations(tmp_path, n=0)
    assert main(["demos", "--tool", "slope", "--out", str(tmp_path)]) == 2
    assert "tool" in capsys.readouterr().err


def test_every_demonstration_reaches_the_target_square(ds: Dataset) -> None:
    assert len(ds.demonstrations) == 8
    for d in ds.demonstrations:
        truth = ds.truth[d.name]
        assert truth["reached_target"] and DEMO_SCENE.in_target(np.array(truth["final_object_xy"]))
        last = d.object_xy[d.t_object >= d.t_object[-1] - 1.0].mean(axis=0)  # the camera's last second
        assert DEMO_SCENE.in_target(last), (d.name, last)


def test_scene_corners_and_every_tool_path_are_inside_the_reach(ds: Dataset) -> None:
    plat = OmniPlatform(a_t=ds.tool().a_t)
    sec = reach_sector(plat)
    r = np.linalg.norm(DEMO_SCENE.corners - sec.centre, axis=1)
    assert np.all((r > sec.r_in) & (r < sec.r_out))
    lo, hi = np.array(plat.limits.lower), np.array(plat.limits.upper)
    for d in ds.demonstrations:
        assert np.all((d.joints >= lo - JOINT_STEP) & (d.joints <= hi + JOINT_STEP)), d.name
        jp = joint_path(plat, d.tool_pose[:, :2])
        assert np.all(jp.violation <= JOINT_STEP), d.name


def test_the_tool_and_the_puck_keep_clear_of_the_obstacle(ds: Dataset) -> None:
    tool = ds.tool()
    xy = np.asarray(tool.outline.exterior.coords)
    for d in ds.demonstrations:
        for obstacle in DEMO_SCENE.obstacles:
            c = to_tool_frame(obstacle.centre, d.tool_pose)
            dist, _ = nearest_on_segments(c, xy[:-1], xy[1:])
            assert dist.min() - obstacle.radius > 0.002, d.name  # the switches keep 3 mm
            puck = np.linalg.norm(d.object_xy - obstacle.centre, axis=1) - obstacle.radius - 0.0175
            assert puck.min() > 0.0, d.name  # camera samples, 1.5 mm noise


def test_ground_truth_follows_the_scene(ds: Dataset) -> None:
    changes = [(a, b) for a, b in zip(DEMO_SCENE.faces, DEMO_SCENE.faces[1:], strict=False) if a != b]
    for d in ds.demonstrations:
        truth = ds.truth[d.name]
        assert [(w["from"], w["to"]) for w in truth["switches"]] == changes
        pushes = truth["pushes"]
        assert all(p["t_end"] - p["t_start"] >= MIN_CONTACT for p in pushes)
        assert all(p["t_end"] < q["t_start"] for p, q in itertools.pairwise(pushes))
        faces = [p["face"] for p in pushes]
        assert [f for i, f in enumerate(faces) if i == 0 or f != faces[i - 1]] == list(DEMO_SCENE.faces)
        for w in truth["switches"]:  # no contact while switching
            assert not any(p["t_start"] < w["t_end"] and w["t_start"] < p["t_end"] for p in pushes)


def test_recordings_are_sensor_like(ds: Dataset) -> None:
    plat = OmniPlatform(a_t=ds.tool().a_t)
    durations = []
    for d in ds.demonstrations:
        assert 29.0 < d.t_object.size / (d.t_object[-1] - d.t_object[0]) < 31.0  # camera, 30 Hz
        dt = np.diff(d.t_tool)  # encoders, 100 Hz (a sample can come early where the operator's moves join)
        assert np.median(dt) == pytest.approx(0.01) and dt.max() <= 0.01 + 1e-9
        steps = d.joints / JOINT_STEP
        assert np.abs(steps - np.round(steps)).max() < 0.01  # quantized joints
        k = np.arange(0, d.t_tool.size, 97)
        fk = np.array([table_pose(plat, q) for q in d.joints[k]])
        assert np.abs(fk[:, :2] - d.tool_pose[k, :2]).max() <= 2e-6  # the tool pose the device reports
        still = d.object_xy[d.t_object < 0.8]  # the puck rests at the start: the spread is the camera's
        assert 0.001 < still.std(axis=0).mean() < 0.002
        durations.append(d.t_tool[-1])
    assert len(set(np.round(durations, 1))) >= 6  # speeds and dwells vary between demonstrations
