"""The tool heading the Omni imposes at a tool position (docs/design.md section 7), in numpy and CasADi.

The tool centre point at world position ``x`` (2,) is reached with the waist angle (forward branch)
``a = phi(x - b) - atan2(d_t, u)``, ``u = sqrt(|x - b|^2 - d_t^2)``, where ``b`` is the joint-1 axis,
``phi`` the polar angle and ``d_t`` the DH tool row's offset; ``a = base_yaw + q1`` and the tool yaw
is ``a - pi/2`` (see :mod:`tooltransfer.planner.planning.oe.face_frame`). This is smooth wherever ``|x - b| > d_t``,
which the reach rows of the switch NLP guarantee (the inner reach radius is larger than ``d_t``), so the
switch NLP can use the heading as a function of position.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.tools.omni.dh import D_TOOL
from tooltransfer.tools.omni.platform import OmniPlatform


def heading(platform: OmniPlatform, xy: ArrayLike) -> NDArray[np.float64]:
    """Tool yaw [rad] (K,) at tool centre points ``xy`` (K, 2) [m] (forward waist branch)."""
    p = np.atleast_2d(np.asarray(xy, dtype=np.float64)) - np.asarray(platform.base_xy)
    r2 = np.einsum("ij,ij->i", p, p)
    u = np.sqrt(np.maximum(r2 - D_TOOL**2, 1e-18))
    return np.arctan2(p[:, 1], p[:, 0]) - np.arctan2(D_TOOL, u) - np.pi / 2


def heading_casadi(platform: OmniPlatform, x: Any, y: Any) -> Any:
    """Tool yaw [rad] at the tool centre point ``(x, y)`` [m] as a CasADi expression (same maths)."""
    import casadi as ca

    dx, dy = x - platform.base_xy[0], y - platform.base_xy[1]
    u = ca.sqrt(dx * dx + dy * dy - D_TOOL**2)
    return ca.atan2(dy, dx) - ca.atan2(D_TOOL, u) - np.pi / 2


def rot(yaw: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrices (..., 2, 2) for yaws (...) [rad]."""
    a = np.asarray(yaw, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def point_path(platform: OmniPlatform, xy: ArrayLike, p: ArrayLike) -> NDArray[np.float64]:
    """World path (K, 2) [m] of the tool-frame point ``p`` (2,) when the tool centre point follows
    ``xy`` (K, 2) with the Omni's heading."""
    xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))
    return xy + np.einsum("kij,j->ki", rot(heading(platform, xy)), np.asarray(p, dtype=np.float64))


def centre_path(
    platform: OmniPlatform, x: ArrayLike, p: ArrayLike, iters: int = 30, tol: float = 1e-13,
    guess: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Inverse of :func:`point_path`: tool centre points (K, 2) [m] whose tool-frame point ``p`` (2,)
    (or one point per sample, (K, 2)) is at ``x`` (K, 2): Newton's method on
    ``c + R(heading(c)) p - x = 0`` per point (the 2 x 2 Jacobian ``I + R'(h) p grad(h)^T`` in closed
    form), from ``c = x - p``, or from ``guess`` (K, 2) when given (:func:`newton_centres`). Newton's
    method rather than the fixed-point iteration on the heading, which contracts only by about
    ``|p| / |x - b|`` per step."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    pa = np.asarray(p, dtype=np.float64)
    if pa.ndim == 1:
        px, py = (float(v) for v in pa)
    else:
        px, py = pa[:, 0], pa[:, 1]
    c = x - pa if guess is None else np.asarray(guess, dtype=np.float64)
    cx, cy, _ = newton_centres(platform, x[:, 0], x[:, 1], px, py, c[:, 0], c[:, 1], iters, tol)
    return np.column_stack([cx, cy])


def newton_centres(
    platform: OmniPlatform, x0: NDArray[np.float64], x1: NDArray[np.float64],
    px: float | NDArray[np.float64], py: float | NDArray[np.float64],
    cx: NDArray[np.float64], cy: NDArray[np.float64], iters: int = 30, tol: float = 1e-13,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """:func:`centre_path` on coordinates, each (K,): the points ``x0, x1`` [m], the tool-frame point
    ``px, py`` [m] (or floats, one for all) and the centres ``cx, cy`` [m] Newton starts from; returns
    the centres' coordinates (K,) [m] and the tool yaw there (K,) [rad] (:func:`heading` of those
    points, the last residual's). The same arithmetic as on (K, 2) arrays, fewer operations (the
    inverse push model runs it often)."""
    bx, by = (float(v) for v in np.asarray(platform.base_xy, dtype=np.float64))

    def residual(cx: NDArray[np.float64], cy: NDArray[np.float64]) -> tuple:
        dx, dy = cx - bx, cy - by
        r2 = dx * dx + dy * dy
        u = np.sqrt(np.maximum(r2 - D_TOOL**2, 1e-18))
        h = np.arctan2(dy, dx) - np.arctan2(D_TOOL, u) - np.pi / 2
        ch, sh = np.cos(h), np.sin(h)
        qx, qy = ch * px - sh * py, sh * px + ch * py  # R(h) p
        return cx + qx - x0, cy + qy - x1, dx, dy, r2, u, qx, qy, h

    fx, fy, dx, dy, r2, u, qx, qy, h = residual(cx, cy)
    size = np.abs(fx) + np.abs(fy)
    for _ in range(iters):
        if size.max() < tol:
            break
        gx = (-dy + D_TOOL * dx / u) / r2  # grad of the heading
        gy = (dx + D_TOOL * dy / u) / r2
        # J = I + (-qy, qx)^T (gx, gy)
        j11, j12, j21, j22 = 1.0 - qy * gx, -qy * gy, qx * gx, 1.0 + qx * gy
        det = j11 * j22 - j12 * j21
        sx, sy = (j22 * fx - j12 * fy) / det, (j11 * fy - j21 * fx) / det
        # damped: a point whose full step would not shrink its residual takes half steps (near the
        # base, where the heading turns fast, a full step from c = x - p can jump past the root)
        alpha = None  # a full step for every point until one needs less
        for _ in range(30):
            tx, ty = (cx - sx, cy - sy) if alpha is None else (cx - alpha * sx, cy - alpha * sy)
            fx, fy, dx, dy, r2, u, qx, qy, h = residual(tx, ty)  # the accepted trial's residual is the next one
            new_size = np.abs(fx) + np.abs(fy)
            worse = (new_size >= size) & (size >= tol)
            if not worse.any():
                break
            alpha = np.where(worse, 0.5, 1.0) if alpha is None else np.where(worse, 0.5 * alpha, alpha)
        cx, cy, size = tx, ty, new_size
    return cx, cy, h


def heading_scalar(platform: OmniPlatform, x: float, y: float) -> float:
    """:func:`heading` of one point ``(x, y)`` [m] in scalar arithmetic (no arrays)."""
    dx, dy = x - float(platform.base_xy[0]), y - float(platform.base_xy[1])
    u = math.sqrt(max(dx * dx + dy * dy - D_TOOL**2, 1e-18))
    return math.atan2(dy, dx) - math.atan2(D_TOOL, u) - math.pi / 2
