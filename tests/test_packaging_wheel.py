"""``pip wheel .`` builds one stable-ABI wheel (``cp311-abi3-<platform>``) whose compiled core loads
and solves, without the experimental ``ext-modules`` warning; without a C compiler the build still
succeeds and leaves the core out (the NumPy core takes over at run time).

The builds run offline on a copy of the sources, with the test environment's setuptools
(``--no-build-isolation``; the test extra asks for the build floor, setuptools >= 77)."""

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
    for name in ("pyproject.toml", "README.md", "__init__.py", "py.typed"):
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


def test_wheel_is_stable_abi_and_its_core_solves(tmp_path: Path) -> None:
    if shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C compiler")
    whl, log = _wheel(tmp_path)
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
