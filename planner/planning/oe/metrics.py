"""Metrics of a push plan, one function for both OE variants, computed on the plan's dense path."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.constraints import HeadingCone, cone_excess
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.oe.push_plan import Push, PushPlan
from tooltransfer.planner.planning.oe.sequence_proxy import reach_distance
from tooltransfer.tools.objects import Disc

if TYPE_CHECKING:
    from tooltransfer.planner.planning.setting import Setting


CONE_BOUND: float = 0.01
"""The hard bound [rad] on a plan's ``cone_violation_max`` (:data:`tooltransfer.planner.planning.solve.HARD_CHECKS`)."""

SPEED_TOL: float = 1e-3
"""Speed [m/s] below which a sample's direction is not measured (:func:`plan_metrics`' default): a path
coming to a stop points anywhere."""


def contact_reach_distance(setting: Setting, face: str, x: NDArray[np.float64], s: NDArray[np.float64],
                           ends: tuple[FaceFrame, FaceFrame] | None = None) -> NDArray[np.float64]:
    """How far [m] (K,) each object position of ``x`` (K, 2) [m] is outside where the Omni holds ``face``
    with its contact at arc length ``s`` (K,) [m] along the face: the largest residual of the exact reach
    region of the frame with its contact there (outer arc, inner circle, the waist's two limits; the fit's
    :func:`~.constraints.reach_constraints` draw the outer arc with chords inside it). The contact's place
    matters: with the contact toward one end of a long face the region moves by millimetres. A frame's
    ``offset`` and arm-plane ``reach`` are affine in the contact's place along the (straight) face, so the
    frames at the ends of its contact range give them everywhere (``ends``: those two frames, when the
    caller has them, :func:`contact_range_ends`)."""
    f = setting.tool.face(face)
    q0, q1 = f.contact_range
    lo, hi = ends if ends is not None else contact_range_ends(setting, face)
    w = (np.asarray(s, dtype=np.float64) / f.length - q0) / (q1 - q0) if q1 > q0 else np.zeros(len(x))
    offset = lo.offset + w * (hi.offset - lo.offset)
    u_in = lo.reach[0] + w * (hi.reach[0] - lo.reach[0])
    u_out = lo.reach[1] + w * (hi.reach[1] - lo.reach[1])
    d = np.asarray(x, dtype=np.float64) - lo.base
    r = np.hypot(d[:, 0], d[:, 1])
    out = [r - np.hypot(u_out, offset), np.hypot(u_in, offset) - r]
    for a, sign in ((lo.waist[0], -1.0), (lo.waist[1], 1.0)):  # the arm's plane at each waist limit
        out.append(sign * (d @ np.array([-np.sin(a), np.cos(a)]) - offset))
    return np.maximum(np.max(out, axis=0), 0.0)


def heading_cone_violation(frame: FaceFrame, push: Push, x: NDArray[np.float64], v: NDArray[np.float64],
                           speed_tol: float) -> float:
    """Largest angle [rad] by which the object's velocity ``v`` (K, 2) [m/s] over ``push``'s samples
    leaves ``frame``'s admissible cone (``push_angle +- theta_b`` in the tool frame) at the tool's real
    heading: the yaw of the push's own poses (the inverse push model's, with the contact where it is on
    the face; the frame's heading is that of its own contact, which a contact elsewhere on a long face
    turns by up to degrees), over samples moving faster than ``speed_tol`` [m/s]. A push without poses
    for its samples is measured at the frame's heading at the object's places ``x`` (K, 2) [m]."""
    if len(push.tool_pose) != len(v):
        return HeadingCone(frame).angle_violation(x, v, speed_tol)
    return cone_excess(v, lambda moving: push.tool_pose[moving, 2] + frame.push_angle, frame.theta_b, speed_tol)


def contact_range_ends(setting: Setting, face: str) -> tuple[FaceFrame, FaceFrame]:
    """``face``'s frames with its contact at either end of its contact range (their geometry only is used:
    built at the whole friction cone, where any face that can push at all has a cone)."""
    q0, q1 = setting.tool.face(face).contact_range
    return (FaceFrame.build(setting, face, s=q0, friction_cone_fraction=1.0),
            FaceFrame.build(setting, face, s=q1, friction_cone_fraction=1.0))


def window_frame(frame: FaceFrame, setting: Setting, s: float) -> FaceFrame:
    """``frame`` (its face and its share of the friction cone: ``push_angle`` and ``theta_b`` kept) with its
    contact at arc length ``s`` [m] along the face (the object's centre in the tool, the arm-plane reach
    [m] and the offset [m] there): the frame a push on a window of the face was fitted in
    (:attr:`~.push_plan.Push.frame_s`)."""
    at = FaceFrame.build(setting, frame.face, s=s / setting.tool.face(frame.face).length, friction_cone_fraction=1.0)
    return replace(frame, centre_in_tool=at.centre_in_tool, reach=at.reach, offset=at.offset, s=at.s)


def _deviation(x: NDArray[np.float64], t: NDArray[np.float64], ref: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance [m] from each point of ``x`` (T, 2) to the universal path ``ref`` (R, 2) at the same
    phase (``ref`` resampled on ``t``)."""
    tr = np.linspace(t[0], t[-1], ref.shape[0])
    r = np.column_stack([np.interp(t, tr, ref[:, j]) for j in range(2)])
    return np.linalg.norm(x - r, axis=1)


def plan_metrics(
    plan: PushPlan,
    frames: Mapping[str, FaceFrame],
    target: NDArray[np.float64],
    setting: Setting,
    *,
    speed_tol: float = SPEED_TOL,
) -> dict[str, float]:
    """The shared metrics of a solved plan.

    Returns a dict with: ``cone_violation_max`` [rad] (largest angle by which the object's motion
    leaves the active face's admissible cone at the tool's real heading, :func:`heading_cone_violation`,
    over samples moving faster than ``speed_tol`` [m/s]: 1 mm/s by default (slower, a path coming to a stop
    points anywhere); the ``qp`` variant fits again at the realised contacts above 5 mrad);
    ``friction_cone_margin_min`` [rad] (least ``atan(mu) - |phi_c|`` over the pushes: negative means
    a contact that would slide); ``contact_edge_margin_min`` [m] (least distance of the contact from
    the ends of its face's usable range: negative means it leaves the face); ``n_recontacts``;
    ``obstacle_clearance_min`` [m] (object edge to obstacle edge, inf without obstacles; below
    ``margin`` means the safety margin is not kept); ``reach_violation_max`` [m] (distance outside
    the active face's exact reach region with its contact where it is, :func:`contact_reach_distance`);
    ``goal_error`` [m]; ``deviation_mean``, ``deviation_max`` [m] (from the universal path at the same
    phase); ``n_pushes``;
    ``path_length`` [m].
    """
    x, v, t = plan.object_xy, plan.object_v, plan.t
    cone, reach = 0.0, 0.0
    ends: dict[str, tuple[FaceFrame, FaceFrame]] = {}  # each face's frames at the ends of its contact range
    windows: dict[tuple[str, float], FaceFrame] = {}  # the frames of the windows pushes were fitted in
    for p in plan.pushes:
        fr = frames[p.face]
        if not np.isnan(p.frame_s) and (len(p.tool_pose) != len(p.samples) or len(p.contact_s) != len(p.samples)):
            if (p.face, p.frame_s) not in windows:  # a push without its poses: the frame it was fitted in
                windows[p.face, p.frame_s] = window_frame(fr, setting, p.frame_s)
            fr = windows[p.face, p.frame_s]
        cone = max(cone, heading_cone_violation(fr, p, x[p.samples], v[p.samples], speed_tol))
        if len(p.contact_s) == len(p.samples):
            if p.face not in ends:
                ends[p.face] = contact_range_ends(setting, p.face)
            off = contact_reach_distance(setting, p.face, x[p.samples], p.contact_s, ends[p.face])
        else:  # a push without its contact's place: the frame's it was fitted in
            off = reach_distance(fr, x[p.samples])
        reach = max(reach, float(off.max(initial=0.0)))
    clear = np.inf
    for o in setting.obstacles:
        if isinstance(o, Disc):
            gap = np.linalg.norm(x - o.centre, axis=1) - o.radius
        else:
            gap = shapely.distance(o, shapely.points(x))
        clear = min(clear, float(gap.min()) - setting.radius)
    dev = _deviation(x, t, plan.universal)
    return {
        "cone_violation_max": cone,
        "friction_cone_margin_min": min((p.cone_margin for p in plan.pushes), default=float("nan")),
        "contact_edge_margin_min": min((p.edge_margin for p in plan.pushes), default=float("nan")),
        "n_recontacts": float(sum(p.recontact for p in plan.pushes)),
        "obstacle_clearance_min": clear,
        "margin": setting.margin,
        "reach_violation_max": reach,
        "goal_error": float(np.linalg.norm(x[-1] - target)),
        "deviation_mean": float(dev.mean()),
        "deviation_max": float(dev.max()),
        "n_pushes": float(len(plan.pushes)),
        "path_length": float(np.sum(np.linalg.norm(np.diff(x, axis=0), axis=1))),
    }
