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
    form), from ``c = x - p``, or from ``guess`` (K, 2) when given. Newton's method rather than the
    fixed-point iteration on the heading, which contracts only by about ``|p| / |x - b|`` per step."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    pa = np.asarray(p, dtype=np.float64)
    if pa.ndim == 1:
        px, py = (float(v) for v in pa)
    else:
        px, py = pa[:, 0], pa[:, 1]
    bx, by = (float(v) for v in np.asarray(platform.base_xy, dtype=np.float64))
    c = x - pa if guess is None else np.array(guess, dtype=np.float64)

    def residual(c: NDArray[np.float64]) -> tuple:
        dx, dy = c[:, 0] - bx, c[:, 1] - by
        r2 = dx * dx + dy * dy
        u = np.sqrt(np.maximum(r2 - D_TOOL**2, 1e-18))
        h = np.arctan2(dy, dx) - np.arctan2(D_TOOL, u) - np.pi / 2
        ch, sh = np.cos(h), np.sin(h)
        qx, qy = ch * px - sh * py, sh * px + ch * py  # R(h) p
        return c[:, 0] + qx - x[:, 0], c[:, 1] + qy - x[:, 1], dx, dy, r2, u, qx, qy

    fx, fy, dx, dy, r2, u, qx, qy = residual(c)
    for _ in range(iters):
        size = np.abs(fx) + np.abs(fy)
        if np.max(size) < tol:
            break
        gx = (-dy + D_TOOL * dx / u) / r2  # grad of the heading
        gy = (dx + D_TOOL * dy / u) / r2
        # J = I + (-qy, qx)^T (gx, gy)
        j11, j12, j21, j22 = 1.0 - qy * gx, -qy * gy, qx * gx, 1.0 + qx * gy
        det = j11 * j22 - j12 * j21
        step = np.column_stack([(j22 * fx - j12 * fy) / det, (j11 * fy - j21 * fx) / det])
        # damped: a point whose full step would not shrink its residual takes half steps (near the
        # base, where the heading turns fast, a full step from c = x - p can jump past the root)
        alpha = np.ones(len(c))
        for _ in range(30):
            trial = c - alpha[:, None] * step
            fx, fy, dx, dy, r2, u, qx, qy = residual(trial)  # the accepted trial's residual is the next one
            worse = (np.abs(fx) + np.abs(fy) >= size) & (size >= tol)
            if not worse.any():
                break
            alpha = np.where(worse, 0.5 * alpha, alpha)
        c = trial
    return c


def heading_scalar(platform: OmniPlatform, x: float, y: float) -> float:
    """:func:`heading` of one point ``(x, y)`` [m] in scalar arithmetic (no arrays)."""
    dx, dy = x - float(platform.base_xy[0]), y - float(platform.base_xy[1])
    u = math.sqrt(max(dx * dx + dy * dy - D_TOOL**2, 1e-18))
    return math.atan2(dy, dx) - math.atan2(D_TOOL, u) - math.pi / 2
