"""Re-planning the rest of a plan from an observed object: the OE side of closed-loop correction.

The closed loop (:func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`) re-solves the rest of
the task with the plan's own condensing whenever the object strays from where the plan in force puts
it. What such a re-plan is made of lives here:

* :class:`PlanReference`: the plan's pushes on their own time axis (switches and approach taken
  out) and, from any time on it, the rest of the plan's object path shifted to start at the observed
  object and blended back to the target, with the rest of the faces and switch times;
* :func:`replan_setting`: the setting from the observed object (the safety margin at most the
  object's clearance there);
* :func:`replan_options`: the friction cone's share widened by :data:`REPLAN_CONE_WIDENING`, and the
  plan's contact budget carried over to the push model in force.

The loop takes a re-plan only where its tool keeps the safety envelope's margin along every push and its first
change of face has a tool path (:meth:`tooltransfer.planner.execution.loop_run.LoopRun.runnable`).

The correction rounds' references, once the plan's path is used up, are
:func:`tooltransfer.planner.planning.oe.correction.correction_references`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.contacts import MIN_PIECE
from tooltransfer.planner.planning.oe.mapping_variant import MappingOptions
from tooltransfer.planner.planning.oe.push_plan import Push, PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.planner.planning.setting import Setting

#: The options of an OE variant (:data:`tooltransfer.planner.planning.variant_registry.OE_VARIANTS`).
Options = TypeVar("Options", QPOptions, MappingOptions)

#: A re-plan may use this many times the share of the friction cone the nominal plan uses (the task's
#: ``oe.friction_cone_fraction``), up to the whole cone (:func:`replan_options`).
REPLAN_CONE_WIDENING = 1.5
#: The most contacts (re-contacts + 1) one push of a re-plan may use (:func:`replan_options`).
MAX_REPLAN_CONTACTS = 30
#: The QP variant's sizes for re-plans (:class:`~tooltransfer.planner.planning.oe.qp_options.QPOptions`): a
#: closed loop re-plans from every strayed observation, on a short rest of the path.
QP_REPLAN_SIZES = {"n_samples": 40, "screen_samples": 30, "n_basis": 15, "candidates": 2, "alternatives": 0}


@dataclass(frozen=True)
class PlanReference:
    """The plan's pushes on their own time axis (``tau`` [s], switches and approach taken out), as a
    push plan whose pushes carry the plan's tool poses.

    Attributes:
        plan: that push plan; spans: per face in a row (re-contacts merged), ``(face, start, end)``
            [s] on ``tau``.
        lead_ins: per push, the plan's own tool path (K, 2) [m] from the previous push's end (its
            switch or re-contact), None for the first.
    """

    plan: PushPlan
    spans: tuple[tuple[str, float, float], ...]
    lead_ins: tuple[NDArray[np.float64] | None, ...]

    @classmethod
    def of(cls, plan: Plan) -> PlanReference:
        """The reference of a solved plan."""
        taus: list[NDArray[np.float64]] = []
        xys: list[NDArray[np.float64]] = []
        poses: list[NDArray[np.float64]] = []
        spans: list[tuple[str, float, float]] = []
        pushes: list[Push] = []
        leads: list[NDArray[np.float64] | None] = []
        now, n = 0.0, 0
        phase = np.asarray(plan.phase)
        prev_end: float | None = None
        for seg in plan.pushes:
            if prev_end is None:
                leads.append(None)
            else:
                between = (plan.t >= prev_end - 1e-9) & (plan.t <= seg.t_start + 1e-9)
                leads.append(plan.tool_pose[between, :2].copy())
            prev_end = seg.t_end
            m = np.flatnonzero((plan.t >= seg.t_start - 1e-9) & (plan.t <= seg.t_end + 1e-9) & (phase == "push"))
            tt = plan.t[m] - seg.t_start + now
            first = 1 if taus else 0  # consecutive pushes share the object's position at the switch
            idx = np.arange(n - first, n - first + m.size)
            taus.append(tt[first:])
            xys.append(plan.object_xy[m][first:])
            poses.append(plan.tool_pose[m])
            face = seg.faces[0]
            end = now + seg.t_end - seg.t_start
            pushes.append(Push(face, now, end, 0.0, idx, plan.tool_pose[m],
                               recontact=bool(pushes) and pushes[-1].face == face))
            if spans and spans[-1][0] == face:  # a re-contact: a re-plan places its own contacts
                spans[-1] = (face, spans[-1][1], end)
            else:
                spans.append((face, now, end))
            now, n = end, n + m.size - first
        tau, xy = np.concatenate(taus), np.vstack(xys)
        v = np.gradient(xy, tau, axis=0) if tau.size > 2 else np.zeros_like(xy)
        return cls(PushPlan(plan.variant.get("oe", "qp"), "solved", tau, xy, v, xy, pushes=tuple(pushes)),
                   tuple(spans), tuple(leads))

    @property
    def tau(self) -> NDArray[np.float64]:
        return self.plan.t

    @property
    def xy(self) -> NDArray[np.float64]:
        return self.plan.object_xy

    def rest(self, tau0: float, start: NDArray[np.float64], target: NDArray[np.float64]) -> tuple:
        """Times (K,) from 0, the reference (K, 2) from ``start`` blended back to the plan by the end
        (and exactly to ``target``), and the faces with their switch times after ``tau0``."""
        keep = self.tau > tau0 + 1e-9
        tt = np.concatenate([[tau0], self.tau[keep]])
        here = [np.interp(tau0, self.tau, self.xy[:, j]) for j in range(2)]
        xy = np.vstack([here, self.xy[keep]])
        u = (tt - tt[0]) / max(tt[-1] - tt[0], 1e-9)
        ref = xy + (1.0 - u)[:, None] * (start - xy[0]) + u[:, None] * (target - xy[-1])
        spans = [(f, max(a, tau0) - tau0, b - tau0) for f, a, b in self.spans if b > tau0 + 1e-9]
        if len(spans) > 1:  # a face with less than MIN_PIECE of the plan left: the next face from here
            ahead = (tt <= tau0 + spans[0][2] + 1e-9)
            if np.sum(np.linalg.norm(np.diff(ref[ahead], axis=0), axis=1)) < MIN_PIECE:
                spans = [(spans[1][0], 0.0, spans[1][2]), *spans[2:]]
        faces = tuple(f for f, _, _ in spans)
        switches = tuple(b for _, _, b in spans[:-1])
        return tt - tau0, ref, faces, switches

    @property
    def end(self) -> float:
        """The last push's end [s] on ``tau``."""
        return float(self.tau[-1])


def replan_setting(setting: Setting, o: NDArray[np.float64]) -> Setting:
    """The setting for a re-plan from the object at ``o`` (2,) [m]: the safety margin at most the
    object's clearance there (an object pushed closer to an obstacle than the margin keeps that
    clearance, as a start touching one does: :func:`tooltransfer.planner.planning.setting.effective_margin`)."""
    import shapely

    from tooltransfer.tools.objects import Disc

    disc = shapely.Point(o).buffer(setting.radius, quad_segs=64)
    gap = min((float(shapely.distance(disc, ob.polygon() if isinstance(ob, Disc) else ob))
               for ob in setting.obstacles), default=np.inf)
    return setting if gap >= setting.margin else replace(setting, margin=max(0.0, gap - 1e-4))


def replan_options(options: Options, c_plan: float, c: float) -> Options:
    """The re-plans' options (any OE variant's, with a ``friction_cone_fraction``).

    The friction cone's share is widened by :data:`REPLAN_CONE_WIDENING` (at most the whole cone):
    the nominal plan keeps part of the cone in reserve so that it survives an error in the
    mechanics, and a re-plan, made from where the object was seen, spends that reserve on the
    correction (a plant whose object drifts toward the face's normal needs directions beyond the
    nominal share to come back).

    Options with a contact budget (the QP variant's ``max_contacts`` per push at the plan's ``c_plan``)
    carry it over to the push model in force (``c``). A sticking contact rolls ``1/c^2`` [m] along the face
    per metre of the object's sideways travel
    (:class:`tooltransfer.planner.planning.oe.constraints.ContactOnFace`), so the sideways travel the task's
    contacts carry at the plan's ``c`` needs ``(c_plan / c)^2`` times as many once the adaptation
    finds a smaller ``c``: the re-plans may use that many (never fewer than the task's, at most
    :data:`MAX_REPLAN_CONTACTS`, which may exceed the task file's bound on ``oe.max_contacts``: that
    bounds what the nominal plan is asked for, this follows from it). Re-contacts are short moves of
    the same face; refusing them would leave the object on the drift the smaller ``c`` causes,
    toward the face's normal.
    """
    update: dict[str, float | int] = {
        "friction_cone_fraction": min(1.0, REPLAN_CONE_WIDENING * options.friction_cone_fraction)}
    if isinstance(options, QPOptions):
        n0 = options.max_contacts
        n = int(np.clip(np.ceil(n0 * (c_plan / c) ** 2 - 1e-9), n0, max(n0, MAX_REPLAN_CONTACTS)))
        if n != n0:
            update["max_contacts"] = n
    return options.model_copy(update=update)
