"""The ``mapping`` variant of OE condensing: the paper's method (section III.A, docs/design.md section 5).

Along the generalized universal path:

1. obstacles: each point is pushed out of every obstacle by the monotone outer map (7) with the
   safety margin delta (``r_b`` = obstacle radius + object radius; a convex polygon obstacle is
   replaced by the disc about its vertices' centroid through its farthest vertex, the paper's
   obstacles being round); far points move less and less (the "tail effect"), but the start and
   target move too, so their displacement is taken out linearly in time (the margin then holds
   only approximately: the metrics report the clearance reached);
2. at each sample the face whose world push direction (heading as the Omni imposes it at that
   object position) is closest to the motion direction is chosen; runs shorter than
   ``min_push`` samples join their neighbour; face changes give the pushes;
3. the motion direction relative to the chosen face is compressed into its cone by (6), the
   compressed steps are integrated and every new point is kept inside a tube of radius ``tube``
   about the universal path by the inner map (7);
4. the end error is removed by a linear blend over the last push so the object reaches the target;
5. the pushes are realised by the same inverse push model as the ``qp`` variant's
   (:mod:`tooltransfer.planner.planning.oe.contacts`: tool poses, the contact rolling along the face, re-contacts where
   one contact cannot carry the travel), so the two variants are compared on equal terms.

The faces' cones are the same admissible cones as the ``qp`` variant's (the friction cone about the
normal, narrowed to the options' ``friction_cone_fraction``, intersected with the tool file's cone; see
:mod:`tooltransfer.planner.planning.oe.face_frame`): (6) compresses the directions into them.

As in the paper there is no reach constraint; the shared metrics show what that costs (cone
violations where the tube pulls the path, reach violations where a face cannot be placed).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.oe_mappings import angle_map, wrap_angle
from tooltransfer.planner.learning.oe_point_mappings import inner_map_points, outer_map_points
from tooltransfer.planner.planning.oe.contacts import PushRefused, realise_pushes
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.oe.metrics import plan_metrics
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.problems.task import OEOptions
from tooltransfer.tools.objects import Disc, Obstacle
from tooltransfer.validation import check_array

_TASK = OEOptions.model_fields


class MappingOptions(BaseModel):
    """Options of the ``mapping`` variant: ``k``, ``tube``, ``friction_cone_fraction``,
    ``contact_margin`` and ``contact_span`` are the task's ``oe`` fields (defaults,
    bounds and descriptions of :class:`tooltransfer.problems.task.OEOptions`, reused), validated
    once by pydantic when built (:meth:`from_task` takes the task's validated values).

    Attributes:
        k: adjusting factor of (6) and (7), in (0, 1).
        tube: radius of the tube about the universal path [m] (inner (7)).
        min_push: shortest push [samples]; shorter runs of one face join their neighbour.
        n_samples: samples of the condensed path.
        friction_cone_fraction: share (0, 1] of the friction cone's half-angle the faces' cones use
            (:meth:`tooltransfer.planner.planning.oe.face_frame.FaceFrame.build`).
        contact_margin, contact_span: where on a face the contact may be [m]
            (:func:`tooltransfer.planner.planning.oe.contacts.usable_range`).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    k: float = _TASK["k"]
    tube: float = _TASK["tube"]
    min_push: int = Field(5, ge=1, strict=True)
    n_samples: int = Field(400, ge=1, strict=True)
    friction_cone_fraction: float = _TASK["friction_cone_fraction"]
    contact_margin: float = _TASK["contact_margin"]
    contact_span: float = _TASK["contact_span"]

    @classmethod
    def from_task(cls, oe: OEOptions) -> MappingOptions:
        """The options of a task's ``oe`` section (validated by the task schema, so not again)."""
        return cls.model_construct(k=oe.k, tube=oe.tube, friction_cone_fraction=oe.friction_cone_fraction,
                                   contact_margin=oe.contact_margin, contact_span=oe.contact_span)


def _as_disc(o: Obstacle) -> Disc:
    if isinstance(o, Disc):
        return o
    ring = np.asarray(o.exterior.coords)[:-1]
    c = ring.mean(axis=0)
    return Disc(c, float(np.linalg.norm(ring - c, axis=1).max()))


def avoid_obstacles(
    x: NDArray[np.float64], obstacles: Sequence[Obstacle], k: float, margin: float, radius: float
) -> NDArray[np.float64]:
    """Push the path ``x`` (T, 2) [m] of an object of ``radius`` [m] out of every obstacle with the
    outer map (7) and ``margin`` [m]."""
    out = x.copy()
    for o in map(_as_disc, obstacles):
        d = np.linalg.norm(out - o.centre, axis=1)
        safe = d > 0  # a point exactly at a centre has no direction to be pushed in: left to the metrics
        out[safe] = outer_map_points(out[safe], o.centre, o.radius + radius, k, delta=margin)
    return out


def _labels(
    x: NDArray[np.float64], v: NDArray[np.float64], frames: list[FaceFrame], min_push: int
) -> NDArray[np.intp]:
    ang = np.arctan2(v[:, 1], v[:, 0])
    off = np.stack([np.abs(wrap_angle(ang - fr.push_direction(x))) for fr in frames], axis=1)
    lab = np.argmin(off, axis=1)
    # drop short runs: each joins the longer of its neighbours
    changed = True
    while changed:
        changed = False
        starts = np.flatnonzero(np.diff(lab, prepend=-1))
        ends = np.append(starts[1:], lab.size)
        lengths = ends - starts
        if lengths.size <= 1:
            break
        i = int(np.argmin(lengths))
        if lengths[i] >= min_push:
            break
        left = lengths[i - 1] if i > 0 else -1
        right = lengths[i + 1] if i + 1 < lengths.size else -1
        lab[starts[i]:ends[i]] = lab[starts[i - 1]] if left >= right else lab[starts[i + 1]]
        changed = True
    return lab


def condense_mapping(
    t: NDArray[np.float64],
    universal: NDArray[np.float64],
    setting: Setting,
    target: NDArray[np.float64] | None = None,
    options: MappingOptions | None = None,
) -> PushPlan:
    """Condense the generalized universal path for ``setting``'s tool by the paper's mappings.

    Args and returns as :func:`tooltransfer.planner.planning.oe.qp_variant.condense_qp`.
    """
    start_time = time.perf_counter()
    opts = options or MappingOptions()
    t = check_array(t, "t", ndim=1)
    universal = check_array(universal, "universal", shape=(t.size, 2))
    target = universal[-1] if target is None else check_array(target, "target", shape=(2,))
    tt = np.linspace(t[0], t[-1], opts.n_samples)
    gen = np.column_stack([np.interp(tt, t, universal[:, j]) for j in range(2)])
    if not isinstance(setting, Setting):
        raise InputError("setting", "a tooltransfer.planner.planning.setting.Setting", type(setting).__name__)
    ref = avoid_obstacles(gen, setting.obstacles, opts.k, setting.margin, setting.radius)
    # the outer map's tail moves every point a little, the start and target too: take the ends'
    # displacement out linearly in time so the path still runs from the start to the target
    s = ((tt - tt[0]) / (tt[-1] - tt[0]))[:, None]
    ref = ref - (1.0 - s) * (ref[0] - gen[0]) - s * (ref[-1] - gen[-1])
    names = list(setting.tool.face_names)
    frames = [FaceFrame.build(setting, f, friction_cone_fraction=opts.friction_cone_fraction) for f in names]
    v_ref = np.gradient(ref, tt, axis=0)
    lab = _labels(ref, v_ref, frames, opts.min_push)
    x = np.empty_like(ref)
    x[0] = gen[0]  # the object starts where it is, whatever the outer map did to the path
    dt = np.diff(tt)
    for i in range(tt.size - 1):
        fr = frames[lab[i]]
        phi = float(fr.push_direction(x[i : i + 1])[0])
        speed = float(np.linalg.norm(v_ref[i]))
        rel = float(wrap_angle(np.arctan2(v_ref[i, 1], v_ref[i, 0]) - phi))
        ang = phi + float(angle_map(rel, fr.theta_b, opts.k))
        step = x[i] + speed * dt[i] * np.array([np.cos(ang), np.sin(ang)])
        x[i + 1] = inner_map_points(step, ref[i + 1], opts.tube, opts.k) if np.any(step != ref[i + 1]) else step
    starts = np.flatnonzero(np.diff(lab, prepend=-1))
    last = int(starts[-1])
    ramp = np.clip((np.arange(tt.size) - last) / max(tt.size - 1 - last, 1), 0.0, 1.0)
    x = x + ramp[:, None] * (target - x[-1])
    v = np.gradient(x, tt, axis=0)
    ends = np.append(starts[1:], tt.size - 1)
    spans = [(names[lab[s]], np.arange(s, e + 1)) for s, e in zip(starts, ends, strict=True)]
    try:
        pushes = realise_pushes(setting, spans, tt, x, opts)
    except PushRefused as exc:
        return PushPlan("mapping", "infeasible", np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)), gen,
                        reason=f"the mapped path cannot be pushed: {exc}",
                        metrics={"compute_time": time.perf_counter() - start_time})
    plan = PushPlan("mapping", "solved", tt, x, v, gen, pushes=pushes)
    metrics = plan_metrics(plan, dict(zip(names, frames, strict=True)), target, setting)
    metrics["compute_time"] = time.perf_counter() - start_time
    return PushPlan("mapping", "solved", tt, x, v, gen, pushes=pushes, metrics=metrics)


__all__ = ["MappingOptions", "avoid_obstacles", "condense_mapping"]
