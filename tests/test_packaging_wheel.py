"""A release from files: ``python -m build`` makes a source distribution and, from it, one stable-ABI
wheel (``cp311-abi3-<platform>``) whose compiled core loads and solves, without the experimental
``ext-modules`` warning; ``twine check`` accepts both, their metadata is complete (licence and its
file, classifiers, keywords, the Python floor, the dependencies and extras), and the wheel installs
into a fresh virtual environment with no index and runs there from an empty folder. Without a C
compiler ``pip wheel`` still succeeds and leaves the core out (the NumPy core takes over at run time).

The builds run offline on a copy of the sources, with the test environment's setuptools
(``--no-build-isolation``; the test extra asks for the build floor, setuptools >= 77, and for build
and twine). The release is built once for the module."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tooltransfer.dmp.qp import native
from tooltransfer.dmp.qp.dual_active_set import DualActiveSet

ROOT = Path(__file__).resolve().parents[1]
pytest.importorskip("setuptools.command.bdist_wheel", reason="the build needs setuptools >= 70.1 (floor 77)")
pytest.importorskip("pip", reason="the builds run pip")


def _sources(dest: Path) -> Path:
    """The files a build reads, without build products."""
    src = dest / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE", "py.typed", *(p.name for p in ROOT.glob("*.py"))):
        shutil.copy2(ROOT / name, src / name)
    skip = shutil.ignore_patterns("__pycache__", "*.so", "*.pyd", "*.egg-info", "build", ".*")
    for pkg in ("dmp", "tools", "planner", "problems"):
        shutil.copytree(ROOT / pkg, src / pkg, ignore=skip)
    return src


def _wheel(tmp: Path, **env: str) -> tuple[Path, str]:
    src, out = _sources(tmp), tmp / "wheels"
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-build-isolation", "--no-deps", "-v", "-w", str(out), str(src)]
    run = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, **env}, timeout=600, check=False)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    wheels = list(out.glob("tooltransfer-*.whl"))
    assert len(wheels) == 1
    return wheels[0], run.stdout + run.stderr


@pytest.fixture(scope="module")
def release(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str]:
    """(sdist, wheel, build log) of ``python -m build`` (the sdist first, the wheel built from it)."""
    pytest.importorskip("build", reason="the release is made with python -m build (the test extra has it)")
    if shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    tmp = tmp_path_factory.mktemp("release")
    src, out = _sources(tmp), tmp / "dist"
    cmd = [sys.executable, "-m", "build", "--no-isolation", "-o", str(out), str(src)]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=900, check=False)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    sdists, wheels = list(out.glob("tooltransfer-*.tar.gz")), list(out.glob("tooltransfer-*.whl"))
    assert len(sdists) == len(wheels) == 1
    return sdists[0], wheels[0], run.stdout + run.stderr


def test_wheel_is_stable_abi_and_its_core_solves(release: tuple[Path, Path, str], tmp_path: Path) -> None:
    _, whl, log = release
    assert "experimental" not in log.lower()
    _, py, abi, plat = whl.stem.rsplit("-", 3)
    if not sysconfig.get_config_var("Py_GIL_DISABLED"):
        assert (py, abi) == ("cp311", "abi3")  # one wheel for every CPython >= 3.11
    assert plat != "any"
    with zipfile.ZipFile(whl) as zf:
        cores = [n for n in zf.namelist() if n.startswith("tooltransfer/dmp/qp/_gi_core.") and not n.endswith(".c")]
        assert len(cores) == 1 and ".abi3." in cores[0]
        lib = Path(zf.extract(cores[0], tmp_path / "unpacked"))
    rng = np.random.default_rng(0)
    n, m = 10, 40
    z_c, g = rng.normal(size=n), rng.normal(size=(m, n))
    g /= np.linalg.norm(g, axis=1)[:, None]
    h = g @ rng.normal(scale=0.3, size=n) + rng.uniform(0.0, 0.2, m)
    zs = []
    for which in (native.CompiledCore(lib), "numpy"):
        with native.using(which):
            st = DualActiveSet(z_c, g, h)
        zs.append(st.solve(lambda _z: (np.zeros((0, n)), np.zeros(0))).copy())
    assert (g @ zs[0] - h).max() <= 1e-12
    np.testing.assert_allclose(zs[0], zs[1], rtol=0, atol=1e-12)


@pytest.mark.skipif(not Path("/bin/false").exists(), reason="needs /bin/false as the failing compiler")
def test_build_without_a_compiler_succeeds_without_the_core(tmp_path: Path) -> None:
    whl, log = _wheel(tmp_path, CC="/bin/false")
    assert 'building extension "tooltransfer.dmp.qp._gi_core" failed' in log
    with zipfile.ZipFile(whl) as zf:
        names = zf.namelist()
    assert "tooltransfer/dmp/qp/_gi_numpy.py" in names and "tooltransfer/dmp/qp/native.py" in names
    # one import name: nothing but the package tooltransfer and the distribution's metadata
    assert {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")} == {"tooltransfer"}
    assert "tooltransfer/__init__.py" in names and "tooltransfer/problems/paper/transfer_tool2.yaml" in names
    assert not [n for n in names if n.startswith("tooltransfer/dmp/qp/_gi_core.") and not n.endswith(".c")]


def test_twine_accepts_the_release_and_its_metadata_is_complete(release: tuple[Path, Path, str]) -> None:
    pytest.importorskip("twine", reason="the test extra has twine")
    import email
    import tarfile
    import tomllib

    sdist, whl, _ = release
    run = subprocess.run([sys.executable, "-m", "twine", "check", "--strict", str(sdist), str(whl)],
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0 and run.stdout.count("PASSED") == 2, run.stdout + run.stderr
    with zipfile.ZipFile(whl) as zf:
        meta = email.message_from_bytes(zf.read("tooltransfer-0.1.0.dist-info/METADATA"))
        assert "tooltransfer-0.1.0.dist-info/licenses/LICENSE" in zf.namelist()
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["License-Expression"] == "MIT" and meta.get_all("License-File") == ["LICENSE"]
    assert meta["Requires-Python"] == ">=3.11" and meta["Summary"] == project["description"]
    assert meta.get_all("Classifier") == project["classifiers"]
    assert "Programming Language :: Python :: 3.11" in project["classifiers"]
    assert meta["Keywords"] and meta["Author"]
    assert len(meta.get_all("Requires-Dist")) > len(project["dependencies"])  # the extras' too
    assert {"sim", "plots", "dask", "all", "test", "docs", "bench"} <= set(meta.get_all("Provides-Extra"))
    assert meta["Description-Content-Type"] == "text/markdown"
    with tarfile.open(sdist) as tf:
        names = {n.split("/", 1)[1] for n in tf.getnames() if "/" in n}
    for needed in ("pyproject.toml", "README.md", "LICENSE", "dmp/qp/_gi_core.c", "dmp/qp/_build.py",
                   "problems/paper/transfer_tool2.yaml", "problems/data/finger_demos/meta.yaml"):
        assert needed in names, needed


def test_the_wheel_installs_into_a_fresh_venv_and_runs(release: tuple[Path, Path, str], tmp_path: Path) -> None:
    """A new environment without pip and without an index: the wheel installed by this environment's pip
    (``--python``), the dependencies seen through a path file (this environment's site-packages, whose
    own path files, among them the editable install of the checkout, are not read)."""
    import sysconfig

    _, whl, _ = release
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    (Path(site) / "dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    run = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--no-index",
                          str(whl)], capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    empty = tmp_path / "empty"
    empty.mkdir()
    code = ("import tooltransfer as tt; from tooltransfer.dmp.qp import native; "
            "task = tt.load_task('paper/transfer_tool2'); "
            "print(tt.__file__); print(native.compiled_path()); print(task.name)")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    run = subprocess.run([str(python), "-c", code], cwd=empty, capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    where, core, name = run.stdout.split()
    assert where.startswith(site) and core.startswith(site) and name == "transfer_tool2"
    run = subprocess.run([str(venv / "bin" / "tooltransfer"), "tasks"], cwd=empty, capture_output=True, text=True,
                         env=env, timeout=120)
    assert run.returncode == 0 and "paper/transfer_tool2" in run.stdout, run.stderr[-2000:]
