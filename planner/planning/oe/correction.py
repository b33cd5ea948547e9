"""Correction references: the ways from an observed object to the target along the faces' normals.

Once the closed loop (:func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`) has used up the
plan's path with the object short of the target, it corrects along the faces' normals, where the
object goes whatever ``c`` (the limit surface) is: one face whose admissible cone
(:class:`~tooltransfer.planner.planning.oe.face_frame.FaceFrame`) holds the way to the target, or the corner
of two faces' normals ``u1``, ``u2`` that splits it, ``r = a u1 + b u2`` with ``a, b > 0``. Each is a
reference (an object path with its faces and switch times) for the sequence fit
(:func:`tooltransfer.planner.planning.oe.qp_variant.condense_sequence`); the straight way with no faces, for a
new search, comes last.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.tools.pose import wrap_angle

#: The shortest this many ways along the faces' normals are tried before the straight way.
CORRECTION_WAYS = 3


class CorrectionReference(NamedTuple):
    """One way to the target: ``faces`` in order (empty: a new search), times ``t`` (K,) [s] from 0
    (one second per centimetre of the way, at least one second), the object path ``ref`` (K, 2) [m]
    from the observed object to the target, the ``switches`` [s] between the faces."""

    faces: tuple[str, ...]
    t: NDArray[np.float64]
    ref: NDArray[np.float64]
    switches: tuple[float, ...]


def _unit(angle: float) -> NDArray[np.float64]:
    return np.array([np.cos(angle), np.sin(angle)])


def correction_references(setting: Setting, friction_cone_fraction: float, o: NDArray[np.float64],
                          target: NDArray[np.float64]) -> list[CorrectionReference]:
    """The references to try, in order, from the object at ``o`` (2,) [m] to ``target`` (2,) [m] in
    ``setting``: the :data:`CORRECTION_WAYS` shortest ways along one face's normal or a corner of two
    (module docstring; the faces' cones for ``friction_cone_fraction``, the plan's share of the
    friction cone), then the straight way with no faces."""
    r = target - o
    d = float(np.hypot(*r))
    frames = {f: FaceFrame.build(setting, f, friction_cone_fraction=friction_cone_fraction)
              for f in setting.tool.face_names}
    normal = {f: _unit(float(fr.normal_direction(o[None])[0])) for f, fr in frames.items()}
    legs: list[tuple[float, tuple[str, ...], NDArray[np.float64]]] = []
    for f, fr in frames.items():
        off = float(wrap_angle(np.arctan2(r[1], r[0]) - fr.push_direction(o[None])[0]))
        if abs(off) <= fr.theta_b:
            legs.append((d, (f,), np.vstack([o, target])))
    for f1 in frames:
        for f2 in frames:
            m = np.column_stack([normal[f1], normal[f2]])
            if f1 == f2 or abs(np.linalg.det(m)) < 1e-3:
                continue
            a, b = np.linalg.solve(m, r)
            if a > 1e-4 and b > 1e-4:
                legs.append((float(a + b), (f1, f2), np.vstack([o, o + a * normal[f1], target])))
    out: list[CorrectionReference] = []
    for length, faces, corners in sorted(legs, key=lambda leg: leg[0])[:CORRECTION_WAYS]:
        seg = np.linalg.norm(np.diff(corners, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        t = np.linspace(0.0, max(1.0, length / 0.01), 40)
        u = np.linspace(0.0, s[-1], t.size)
        ref = np.column_stack([np.interp(u, s, corners[:, j]) for j in range(2)])
        switches = (float(t[-1] * s[1] / s[-1]),) if len(faces) == 2 else ()
        out.append(CorrectionReference(faces, t, ref, switches))
    out.append(straight_reference(o, target))
    return out


def straight_reference(o: NDArray[np.float64], target: NDArray[np.float64]) -> CorrectionReference:
    """The straight way from the object at ``o`` (2,) [m] to ``target`` (2,) [m] with no faces, the last
    of :func:`correction_references` (30 samples, 1 s per cm, at least 1 s)."""
    r = target - o
    t = np.linspace(0.0, max(1.0, float(np.hypot(*r)) / 0.01), 30)
    return CorrectionReference((), t, o + np.linspace(0.0, 1.0, t.size)[:, None] * r, ())
