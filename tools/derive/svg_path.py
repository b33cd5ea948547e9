"""An SVG path's ``d`` string as a polygon: lines kept, curves and arcs replaced by chords.

Commands ``M L H V C S Q T A Z`` (absolute and relative, as in SVG 1.1 section 8.3) of one closed
subpath. Cubic and quadratic Bezier curves are split in halves until their control points lie within
``tolerance`` of the chord (de Casteljau; the curve then lies within it too); an elliptical arc is
replaced by chords whose sagitta is at most ``tolerance`` on its larger radius. Coordinates are in the
path's own units; :func:`svg_polygon` scales them and flips y (SVG's y axis points down).
"""

from __future__ import annotations

import re

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError

_TOKEN = re.compile(r"[MmLlHhVvCcSsQqTtAaZz]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_ARITY = {"M": 2, "L": 2, "H": 1, "V": 1, "C": 6, "S": 4, "Q": 4, "T": 2, "A": 7, "Z": 0}
#: Most points a path may flatten to (the tool file's bound on outline vertices is lower).
MAX_POINTS = 100_000


def _bezier(ctrl: NDArray[np.float64], tol: float, out: list[NDArray[np.float64]], depth: int = 0) -> None:
    """Append the end points of chords within ``tol`` of the Bezier curve ``ctrl`` (k, 2) (its start excluded)."""
    a, b = ctrl[0], ctrl[-1]
    chord = b - a
    n = float(np.hypot(*chord))
    inner = ctrl[1:-1] - a
    dev = np.abs(chord[0] * inner[:, 1] - chord[1] * inner[:, 0]) / n if n > 0 else np.hypot(*inner.T)
    if depth >= 24 or dev.max(initial=0.0) <= tol:
        out.append(b.copy())
        return
    left, right = [ctrl[0]], [ctrl[-1]]
    pts = ctrl.copy()
    while len(pts) > 1:
        pts = 0.5 * (pts[1:] + pts[:-1])
        left.append(pts[0])
        right.append(pts[-1])
    _bezier(np.array(left), tol, out, depth + 1)
    _bezier(np.array(right[::-1]), tol, out, depth + 1)


def _arc(p0: NDArray[np.float64], args: list[float], tol: float) -> list[NDArray[np.float64]]:
    """Chords of the SVG elliptical arc from ``p0`` (endpoint parameterisation, SVG 1.1 appendix F.6)."""
    rx, ry, phi_deg, large, sweep, x, y = args
    p1 = np.array([x, y])
    rx, ry = abs(rx), abs(ry)
    if rx == 0 or ry == 0 or np.allclose(p0, p1):
        return [p1]
    phi = np.radians(phi_deg)
    cp, sp = np.cos(phi), np.sin(phi)
    d = 0.5 * (p0 - p1)
    x1, y1 = cp * d[0] + sp * d[1], -sp * d[0] + cp * d[1]
    lam = x1**2 / rx**2 + y1**2 / ry**2
    if lam > 1:
        rx, ry = rx * np.sqrt(lam), ry * np.sqrt(lam)
    num = max(rx**2 * ry**2 - rx**2 * y1**2 - ry**2 * x1**2, 0.0)
    k = np.sqrt(num / (rx**2 * y1**2 + ry**2 * x1**2)) * (-1 if bool(large) == bool(sweep) else 1)
    cx1, cy1 = k * rx * y1 / ry, -k * ry * x1 / rx
    centre = np.array([cp * cx1 - sp * cy1, sp * cx1 + cp * cy1]) + 0.5 * (p0 + p1)
    t0 = np.arctan2((y1 - cy1) / ry, (x1 - cx1) / rx)
    t1 = np.arctan2((-y1 - cy1) / ry, (-x1 - cx1) / rx)
    dt = t1 - t0
    if sweep and dt < 0:
        dt += 2 * np.pi
    elif not sweep and dt > 0:
        dt -= 2 * np.pi
    r = max(rx, ry)
    step = 2 * np.arccos(max(1.0 - tol / r, -1.0)) if tol < r else np.pi / 2
    n = max(1, int(np.ceil(abs(dt) / step)))
    ts = t0 + dt * np.arange(1, n + 1) / n
    pts = [centre + np.array([cp * rx * np.cos(t) - sp * ry * np.sin(t), sp * rx * np.cos(t) + cp * ry * np.sin(t)])
           for t in ts[:-1]]
    return [*pts, p1]


def flatten_path(d: str, tolerance: float) -> NDArray[np.float64]:
    """Vertices (N, 2) of the one closed subpath of the SVG path data ``d`` (path units).

    Raises:
        InputError: an unknown command, a wrong number of arguments, more than one subpath, or
            fewer than three distinct vertices.
    """
    tokens = _TOKEN.findall(d)
    if "".join(tokens).replace(" ", "") == "" or re.sub(r"[\s,]", "", d) != "".join(tokens):
        raise InputError("outline", "SVG path data (commands M L H V C S Q T A Z and numbers)", d[:100])
    pts: list[NDArray[np.float64]] = []
    cur, start = np.zeros(2), np.zeros(2)
    last_ctrl: NDArray[np.float64] | None = None
    cmd, i, moves = "", 0, 0
    while i < len(tokens):
        if tokens[i].isalpha():
            cmd, i = tokens[i], i + 1
        elif not cmd:
            raise InputError("outline", "SVG path data starting with a command", tokens[i])
        up, rel = cmd.upper(), cmd.islower()
        n = _ARITY[up]
        args = [float(v) for v in tokens[i:i + n]]
        if len(args) < n or any(t.isalpha() for t in tokens[i:i + n]):
            raise InputError("outline", f"{n} numbers after the SVG command {cmd}", " ".join(tokens[i:i + n]))
        i += n
        base = cur if rel else np.zeros(2)
        ctrl_next: NDArray[np.float64] | None = None
        if up == "M":
            moves += 1
            if moves > 1:
                raise InputError("outline", "one closed SVG subpath (one M command)", f"{moves} subpaths")
            cur = start = base + args
            pts.append(cur.copy())
            cmd = "l" if rel else "L"  # further pairs are lines
        elif up == "Z":
            cur = start
        elif up in ("L", "H", "V"):
            new = cur.copy() if up != "L" else base + args
            if up == "H":
                new[0] = args[0] + (cur[0] if rel else 0.0)
            elif up == "V":
                new[1] = args[0] + (cur[1] if rel else 0.0)
            cur = new
            pts.append(cur.copy())
        elif up == "A":
            end = base + args[5:7]
            pts += _arc(cur, [*args[:5], *end], tolerance)
            cur = end
        else:
            vals = np.array(args).reshape(-1, 2) + base
            if up in ("S", "T"):
                refl = 2 * cur - last_ctrl if last_ctrl is not None else cur.copy()
                vals = np.vstack([refl, vals])
            ctrl = np.vstack([cur, vals])
            _bezier(ctrl, tolerance, pts)
            ctrl_next, cur = ctrl[-2], ctrl[-1]
        last_ctrl = ctrl_next if (up in ("C", "S", "Q", "T")) else None
        if len(pts) > MAX_POINTS:
            raise InputError("outline", f"a path of at most {MAX_POINTS} vertices at this tolerance", "more")
    ring = np.array(pts)
    if len(ring) > 1 and np.allclose(ring[0], ring[-1]):
        ring = ring[:-1]
    keep = np.ones(len(ring), dtype=bool)
    keep[1:] = np.any(np.abs(np.diff(ring, axis=0)) > 0, axis=1)
    ring = ring[keep]
    if len(ring) < 3:
        raise InputError("outline", "a closed SVG path with at least 3 distinct vertices", str(len(ring)))
    return ring
