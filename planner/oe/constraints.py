"""Constraints of a push on the Omni, as constraint families of the constrained DMP fit.

* :class:`HeadingCone`: the object's velocity inside the pushing face's cone, whose direction turns
  with the tool heading (which follows the Omni's waist, hence the object's position): the rows
  are linearised at the current path and re-built in the sequential loop (family ``"cone"``).
* :func:`reach_constraints`: the object positions from which the face can push it lie in an
  annular sector about the joint-1 axis (:mod:`planner.oe.face_frame`); its two straight sides are
  exact half-planes, its outer arc is replaced by chords inside it and its inner arc by a tangent
  half-plane linearised at the current path (conservative), family ``"reach"``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from dmp.errors import InputError
from dmp.qp.constraints import OutsideDisc, PositionPolygon
from dmp.qp.constraints.base import Coefficients, Constraint
from planner.oe.face_frame import FaceFrame


class HeadingCone(Constraint):
    """Velocity in the cone of half-angle ``theta_b`` about the face's world push direction, which
    depends on the object's position through the Omni's heading (``frame.push_direction``).

    The rows at each sample use the direction at the linearisation path; evaluated on the path
    itself they measure the true violation [m/s].
    """

    linearised = True
    conservative = False

    def __init__(self, frame: FaceFrame, *, family: str = "cone", window: tuple[float, float] | None = None) -> None:
        super().__init__(family, window)
        self.frame = frame

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        if x_lin.shape[1] != 2:
            raise InputError("HeadingCone", "a planar (2-D) motion", f"{x_lin.shape[1]}-D")
        phi = self.frame.push_direction(x_lin[k])
        hi, lo = phi + self.frame.theta_b, phi - self.frame.theta_b
        n1 = np.stack([np.sin(hi), -np.cos(hi)], axis=1)  # inward normals of the two edges
        n2 = np.stack([-np.sin(lo), np.cos(lo)], axis=1)
        a_vel = -np.stack([n1, n2], axis=1)  # (K, 2, 2): -n . v <= 0
        return Coefficients(k, None, a_vel, np.zeros((k.size, 2)))

    def angle_violation(self, x: NDArray[np.float64], v: NDArray[np.float64], speed_tol: float = 1e-6) -> float:
        """Largest angle [rad] by which the velocity leaves the cone, over samples moving faster
        than ``speed_tol`` [m/s] (x, v of shape (K, 2) at the constraint's samples)."""
        speed = np.linalg.norm(v, axis=1)
        moving = speed > speed_tol
        if not np.any(moving):
            return 0.0
        ang = np.arctan2(v[moving, 1], v[moving, 0]) - self.frame.push_direction(x[moving])
        off = np.abs((ang + np.pi) % (2 * np.pi) - np.pi)
        return float(max(0.0, (off - self.frame.theta_b).max()))


def _chords(frame: FaceFrame, tol: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Half-planes of chords inside the outer arc (radius ``hypot(u_out, offset)``) within ``tol``."""
    u_out = frame.reach[1]
    r_out = float(np.hypot(u_out, frame.offset))
    g = float(np.arctan2(frame.offset, u_out))
    lo, hi = frame.waist[0] + min(g, 0.0), frame.waist[1] + max(g, 0.0)
    half = float(np.arccos(r_out / (r_out + tol)))
    n = max(1, int(np.ceil((hi - lo) / (2.0 * half))))
    mids = lo + (np.arange(n) + 0.5) * (hi - lo) / n
    g_rows = np.stack([np.cos(mids), np.sin(mids)], axis=1)
    return g_rows, r_out * np.cos(0.5 * (hi - lo) / n) + g_rows @ frame.base


def reach_constraints(
    frame: FaceFrame, *, window: tuple[float, float] | None = None, tol: float = 2e-4, family: str = "reach"
) -> list[Constraint]:
    """Constraints keeping the object where ``frame``'s face can push it from (inner approximation
    within ``tol`` [m] of the exact sector on the outer arc)."""
    rows_g, rows_h = [], []
    for a, sign in ((frame.waist[0], -1.0), (frame.waist[1], 1.0)):
        n = np.array([-np.sin(a), np.cos(a)])  # direction of increasing waist angle at that side
        rows_g.append(sign * n)
        rows_h.append(sign * (frame.offset + n @ frame.base))
    cg, ch = _chords(frame, tol)
    polygon = PositionPolygon(np.vstack([np.array(rows_g), cg]), np.concatenate([rows_h, ch]), family=family,
                              window=window)
    r_in = float(np.hypot(frame.reach[0], frame.offset))
    return [polygon, OutsideDisc(frame.base, r_in, family=family, window=window)]
