"""The fixed points of a segmentation given by the caller: checked arrays, and the ``--fixed-points`` file.

A fixed point is where the object rests during a switch (a corner where the active face changes); the
segmentation finds them (:func:`tooltransfer.planner.learning.segmentation.core.segment`) unless the caller gives
them, as an (F, 2) array [m] per demonstration.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError

__all__ = ["fixed_point_array", "load_fixed_points"]


def fixed_point_array(points: object, field: str = "fixed_points") -> NDArray[np.float64]:
    """Fixed points as an (F, 2) array [m]: a list of ``[x, y]`` pairs of finite numbers (not booleans
    or strings); errors name ``field`` and the entry."""
    if not isinstance(points, list | tuple | np.ndarray):
        raise InputError(field, "a list of [x, y] points [m]", type(points).__name__)
    for i, pt in enumerate(points):
        if not isinstance(pt, list | tuple | np.ndarray) or len(pt) != 2:
            raise InputError(f"{field}[{i}]", "a point [x, y] [m]", repr(pt)[:60])
        for j, v in enumerate(pt):
            if isinstance(v, bool | np.bool_) or not isinstance(v, int | float | np.integer | np.floating) \
                    or not np.isfinite(v):
                raise InputError(f"{field}[{i}][{j}]", "a finite number [m]", repr(v)[:60])
    return np.asarray(points, dtype=np.float64).reshape(-1, 2)


def load_fixed_points(path: str | Path, names: Sequence[str] = (), option: str = "--fixed-points"
                      ) -> dict[str, NDArray[np.float64]]:
    """A ``--fixed-points`` file: JSON ``{demo name: [[x, y], ...]}`` [m]; every entry checked (and,
    given ``names``, every key a demonstration's name), errors naming the ``option``, the file and the
    entry."""
    import json

    from tooltransfer.regular_file import read_regular

    where = f"{option} {path}".strip()
    try:
        p = Path(path)
        if p.stat().st_size > 16 * 2**20:
            raise InputError(f"{where}", "a fixed-points file of at most 16 MB", f"{p.stat().st_size} bytes")
        raw = read_regular(p, lambda _p, _w, e, g: InputError(where, e, g), "fixed-points file", 16 * 2**20)
        data = json.loads(raw.decode("utf-8-sig"))
    except OSError as exc:
        raise InputError(f"{where}", "a readable JSON file {demo name: [[x, y], ...]} [m]", exc.strerror) from None
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise InputError(f"{where}", "a JSON file {demo name: [[x, y], ...]} [m]",
                         str(exc)[:120] if not isinstance(exc, RecursionError) else "JSON nested too deep") from None
    if not isinstance(data, dict):
        raise InputError(f"{where}", "a JSON object {demo name: [[x, y], ...]} [m]", type(data).__name__)
    out = {}
    for name, pts in data.items():
        if names and name not in names:
            raise InputError(f"{where}: {name[:60]}", f"a demonstration's name ({', '.join(names)})", repr(name[:60]))
        out[name] = fixed_point_array(pts, f"{where}: {name[:60]}")
    return out
