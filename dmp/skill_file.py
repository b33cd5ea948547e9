"""Versioned skill files: a fitted DMP as self-describing JSON.

Format ``tooltransfer.dmp/1``::

    {"format": "tooltransfer.dmp/1",
     "formulation": "<equations in words>",
     "n_dims", "n_basis", "alpha_z", "beta_z", "gamma", "scaling", "ridge", "fit_method",
     "tau" [s], "x0" [m], "g" [m], "centres", "widths", "weights" (N x n)}
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from tooltransfer.errors import InputError, SkillFileError

if TYPE_CHECKING:
    from tooltransfer.dmp.primitive import DMP

FORMAT = "tooltransfer.dmp"
VERSION = 1
FORMULATION = (
    "tau*dv/dt = alpha_z*(beta_z*(g - x) - v) + f(s); tau*dx/dt = v; tau*ds/dt = -gamma*s; "
    "f(s) = M(x0, g) @ W.T @ psi(s); psi_i = phi_i*s/sum_j phi_j; phi_i = exp(-h_i*(s - c_i)^2)"
)


def dmp_to_dict(d: DMP) -> dict[str, Any]:
    """Plain-data description of a fitted DMP (JSON-serialisable)."""
    return {
        "format": f"{FORMAT}/{VERSION}",
        "formulation": FORMULATION,
        "n_dims": d.n_dims,
        "n_basis": d.n_basis,
        "alpha_z": d.alpha_z,
        "beta_z": d.beta_z,
        "gamma": d.gamma,
        "scaling": d.scaling,
        "ridge": d.ridge,
        "fit_method": d.fit_method,
        "tau": d.tau,
        "x0": d.x0.tolist(),
        "g": d.g.tolist(),
        "centres": d.centres.tolist(),
        "widths": d.widths.tolist(),
        "weights": d.weights.tolist(),
    }


def dmp_from_dict(data: dict[str, Any], source: str = "<dict>") -> DMP:
    """Rebuild a DMP from :func:`dmp_to_dict` output; raises :class:`SkillFileError`."""
    from tooltransfer.dmp.primitive import DMP

    if not isinstance(data, dict) or "format" not in data:
        raise SkillFileError(source, "not a tooltransfer skill file (no 'format' field)")
    fmt = str(data["format"])
    name, _, ver = fmt.partition("/")
    if name != FORMAT:
        raise SkillFileError(source, f"format {fmt!r} is not {FORMAT!r}")
    if ver != str(VERSION):
        raise SkillFileError(source, f"format version {ver!r} is not supported (this library reads {VERSION})")
    try:
        d = DMP(
            n_dims=int(data["n_dims"]),
            n_basis=int(data["n_basis"]),
            alpha_z=float(data["alpha_z"]),
            beta_z=float(data["beta_z"]),
            gamma=float(data["gamma"]),
            scaling=data["scaling"],
            ridge=float(data["ridge"]),
        )
        w = np.asarray(data["weights"], dtype=np.float64)
        if w.shape != (d.n_basis, d.n_dims) or not np.all(np.isfinite(w)):
            raise SkillFileError(
                source, f"'weights' must be finite with shape ({d.n_basis}, {d.n_dims}), got {w.shape}"
            )
        for key in ("centres", "widths"):
            stored = np.asarray(data[key], dtype=np.float64)
            expect = d.centres if key == "centres" else d.widths
            if stored.shape != expect.shape or not np.allclose(stored, expect, rtol=1e-12, atol=0):
                raise SkillFileError(source, f"'{key}' disagree with n_basis and gamma (corrupted file?)")
        d.weights = w
        d.tau = float(data["tau"])
        d.x0 = np.asarray(data["x0"], dtype=np.float64).reshape(d.n_dims)
        d.g = np.asarray(data["g"], dtype=np.float64).reshape(d.n_dims)
        d.fit_method = data.get("fit_method")
    except KeyError as exc:
        raise SkillFileError(source, f"missing field {exc.args[0]!r}") from exc
    except (TypeError, ValueError, InputError) as exc:
        raise SkillFileError(source, f"invalid value: {exc}") from exc
    return d


def save_dmp(d: DMP, path: str | Path) -> None:
    """Write ``d`` to ``path`` as JSON, atomically: a temporary file beside it, flushed to disk,
    replaces it in one step (so no half-written skill file is ever left; the same as
    ``tooltransfer.problems.atomic``, kept here so that ``dmp`` depends on no other package)."""
    import os
    import secrets

    target = Path(path)
    tmp = target.with_name(f".{target.name[:200]}.{os.getpid()}-{secrets.token_hex(4)}.tmp")
    try:
        with open(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), "w", encoding="utf-8") as fh:
            fh.write(json.dumps(dmp_to_dict(d), indent=1))
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def read_json(path: str | Path) -> Any:
    """Parsed JSON of a skill file; a missing file or invalid JSON raises :class:`SkillFileError`."""
    p = Path(path)
    try:
        return json.loads(p.read_text())
    except FileNotFoundError as exc:
        raise SkillFileError(str(p), "file not found") from exc
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SkillFileError(str(p), f"not valid JSON ({exc})") from exc


def load_dmp(path: str | Path) -> DMP:
    """Read a DMP written by :func:`save_dmp`."""
    return dmp_from_dict(read_json(path), str(path))
