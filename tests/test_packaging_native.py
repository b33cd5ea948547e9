"""The ctypes layer checks every argument of the compiled core, which is built against the stable
ABI through the supported setuptools commands (no experimental ``ext-modules`` table)."""

from __future__ import annotations

import ast
import sysconfig
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

from tooltransfer.dmp.qp import native
from tooltransfer.dmp.qp.pool import RowPool, Samples
from tooltransfer.dmp.qp.problem import unconstrained_weights
from tooltransfer.problems.fit_cases import l_push_case

ROOT = Path(__file__).resolve().parents[1]
compiled = pytest.mark.skipif(native.compiled_path() is None, reason="the compiled core is not built")


@pytest.fixture
def cc() -> native.CompiledCore:
    path = native.compiled_path()
    assert path is not None
    return native.CompiledCore(path)


def _work(n: int = 6) -> native.GIWork:
    return native.GIWork(np.arange(n, dtype=np.float64))


@compiled
def test_the_built_core_is_the_stable_abi_file() -> None:
    if sysconfig.get_config_var("Py_GIL_DISABLED"):
        pytest.skip("free-threaded CPython builds the version-specific file")
    path = native.compiled_path()
    assert path is not None and path.name.startswith("_gi_core.abi3.")


@compiled
def test_solver_arguments_are_checked_against_the_dimensions(cc: native.CompiledCore) -> None:
    w = _work(6)
    g, h = np.ones((4, 6)), np.ones(4)
    assert cc.gi_solve(w, g, h, 1e-13, 100)[0] == native.NEED_ROWS
    with pytest.raises(ValueError, match="G has shape"):
        cc.gi_solve(w, np.ones((4, 5)), h, 1e-13, 100)  # rows of the wrong length
    with pytest.raises(ValueError, match="G has shape"):
        cc.gi_solve(w, g, np.ones(5), 1e-13, 100)  # more bounds than rows
    with pytest.raises(ValueError, match="C-contiguous"):
        cc.gi_solve(w, np.asfortranarray(g), h, 1e-13, 100)
    with pytest.raises(ValueError, match="float64"):
        cc.gi_solve(w, g.astype(np.float32), h, 1e-13, 100)
    with pytest.raises(ValueError, match="e has shape"):
        cc.gi_equality(w, np.ones(7), 0.0)
    with pytest.raises(ValueError, match="out of range"):
        cc.gi_warm(w, g, h, np.array([0, 4], dtype=np.int32))
    with pytest.raises(ValueError, match="int32"):
        cc.gi_warm(w, g, h, np.array([0, 1]))
    w.n_eq = 3  # more equalities than active rows
    with pytest.raises(ValueError, match="active rows"):
        cc.gi_solve(w, g, h, 1e-13, 100)


def test_state_arrays_cannot_be_rebound() -> None:
    w = _work(6)
    w.z += 1.0  # in place: allowed
    w.n_eq = 0
    with pytest.raises(AttributeError, match="fixed"):
        w.Q = np.eye(3)
    with pytest.raises(AttributeError, match="fixed"):
        w.n = 3


def _pool() -> tuple[RowPool, np.ndarray, Samples]:
    prob = l_push_case(10, 40).problem
    aff = prob.affine("dense")
    w = unconstrained_weights(*prob.quadratic())
    pool = RowPool.build(prob.constraints, aff, aff.positions(w))
    return pool, w, Samples.of(aff, slice(None))


@compiled
def test_scan_and_row_arguments_are_checked(cc: native.CompiledCore) -> None:
    pool, _, smp = _pool()
    pa = pool._core_arrays()
    n_l = smp.idx.size
    x = np.zeros((n_l, pa.n))
    out_s, out_t = np.zeros(8, dtype=np.int32), np.zeros(8, dtype=np.int64)
    idx, buf = smp.idx.astype(np.int64), np.zeros(n_l)
    assert cc.gi_scan(pa, x, x, 0.0, None, out_s, out_t, idx, 0, 0, buf) >= 0
    with pytest.raises(ValueError, match="v has shape"):
        cc.gi_scan(pa, x, x[:-1], 0.0, None, out_s, out_t, idx, 0, 0, buf)
    with pytest.raises(ValueError, match="idx has shape"):
        cc.gi_scan(pa, x, x, 0.0, None, out_s, out_t, idx[:-1], 0, 0, buf)
    bad = idx.copy()
    bad[-1] = pa.T
    with pytest.raises(ValueError, match="out of range"):
        cc.gi_scan(pa, x, x, 0.0, None, out_s, out_t, bad, 0, 0, buf)
    with pytest.raises(ValueError, match="slice out of range"):
        cc.gi_scan(pa, x, x, 0.0, None, out_s, out_t, idx, 1, 1, buf)  # samples 1 .. T: one past the end
    with pytest.raises(ValueError, match="res has shape"):
        cc.gi_scan(pa, x, x, 0.0, np.zeros((pa.S, n_l - 1)), out_s, out_t, idx, 0, 0, buf)
    with pytest.raises(ValueError, match="out_t has shape"):
        cc.gi_scan(pa, x, x, 0.0, None, out_s, out_t[:-1], idx, 0, 0, buf)
    with pytest.raises(ValueError, match="buf"):
        cc.gi_scan(pa, x, x, 0.0, None, out_s, out_t, idx, 0, 0, buf[:-1])
    ids = np.array([0, pa.series_of.size - 1], dtype=np.int64)
    g, h = np.zeros((2, pa.N * pa.n)), np.zeros(2)
    cc.gi_rows(pa, ids, g, h)
    with pytest.raises(ValueError, match="out of range"):
        cc.gi_rows(pa, ids + 1, g, h)
    with pytest.raises(ValueError, match="G has shape"):
        cc.gi_rows(pa, ids, g[:, :-1], h)
    with pytest.raises(ValueError, match="h has shape"):
        cc.gi_rows(pa, ids, g, h[:1])


def test_pool_arrays_are_checked_at_creation() -> None:
    pool, _, _ = _pool()
    pa = pool._core_arrays()
    args = [pa.nb, pa.apos, pa.avel, pa.series_of, pa.sample_of, pa.Gx, pa.Gv, pa.xf, pa.vf, pa.M]
    native.PoolArrays(*args, pa.vfrom)
    short = list(args)
    short[5] = pa.Gx[:-1]  # one sample short
    with pytest.raises(ValueError, match="Gx has shape"):
        native.PoolArrays(*short, pa.vfrom)
    wrong = list(args)
    wrong[4] = pa.sample_of + pa.T  # samples past the grid
    with pytest.raises(ValueError, match="out of range"):
        native.PoolArrays(*wrong, pa.vfrom)
    with pytest.raises(ValueError, match="series ranges"):
        native.PoolArrays(*args, pa.S + 1)
    with pytest.raises(AttributeError, match="fixed"):
        pa.nb = pa.nb.copy()


def test_pyproject_builds_the_core_through_supported_commands() -> None:
    """No ``[tool.setuptools] ext-modules`` (experimental: it warns at every install); the command
    classes named in ``[tool.setuptools.cmdclass]`` exist in the build helper."""
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())
    st = cfg["tool"]["setuptools"]
    assert "ext-modules" not in st
    assert "distutils" not in cfg["tool"]  # experimental too
    helper = ROOT / "dmp" / "qp" / "_build.py"
    classes = {n.name for n in ast.walk(ast.parse(helper.read_text())) if isinstance(n, ast.ClassDef)}
    for cmd, target in st["cmdclass"].items():
        module, _, cls = target.rpartition(".")
        assert module == "tooltransfer.dmp.qp._build" and cls in classes and cls == cmd
    assert {"build_ext", "bdist_wheel", "editable_wheel", "sdist"} <= set(st["cmdclass"])


def test_build_helper_declares_an_optional_stable_abi_extension() -> None:
    with warnings.catch_warnings():  # setuptools may warn about the stdlib distutils it replaces
        warnings.simplefilter("ignore", DeprecationWarning)
        pytest.importorskip("setuptools.command.bdist_wheel")  # setuptools >= 70.1, as the build uses
        from tooltransfer.dmp.qp import _build

    ext = _build.core_extension()
    assert ext.name == "tooltransfer.dmp.qp._gi_core" and ext.sources == ["dmp/qp/_gi_core.c"]
    assert ext.optional  # no compiler: the build goes on, the NumPy core takes over
    if _build.STABLE_ABI:
        assert ext.py_limited_api and ("Py_LIMITED_API", "0x030B0000") in ext.define_macros
        assert _build.LIMITED_API == "cp311"
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"]
    assert requires == ">=3.11"  # the limited API version above
