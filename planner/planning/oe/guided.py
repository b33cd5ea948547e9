"""A push sequence found by a best-first search over puck positions, for the ``qp`` fit to refine.

Where the scored candidates of :func:`~tooltransfer.planner.planning.oe.qp_variant.condense_qp` hold no
feasible sequence, the search here looks for one directly: from the start, straight steps of ``step`` [m]
along the edges and the middle of each face's heading cone (the plan's narrowed friction cone intersected with
the tool file's cone, turned by the heading the Omni imposes; inside it at both ends of the step, since it
turns as the object moves), the face held under the fit's own rows (the Omni reaching the contact at both ends
of its usable range, the tool outline there clear of the obstacles), the puck the safety margin from them; A*
on the path length plus a price per face change (weighted A* in the attempts on windows where needed), ending
with a straight step to the target inside a cone. Each step rolls the contact along its face as the inverse
push model has it (``1/c^2`` times the step's sideways travel, ``R`` per radian the heading turns;
:mod:`tooltransfer.tools.pushing.inverse`); a run of one face starts a new contact (a re-contact) where the
contact's excursion would outgrow the face's usable range, and uses at most ``oe.max_contacts`` contacts, as
one push of the fit may. Its faces and the times of their changes (in proportion to the path's length, over
the universal path's duration) are then fitted by
:func:`~tooltransfer.planner.planning.oe.qp_variant.condense_sequence` with the path as reference, which
imposes every constraint of the ``qp`` variant, or, where that one fit fails, run by run
(:func:`~tooltransfer.planner.planning.oe.piecewise.fit_runs`, the object at rest at each change of face); the
search only proposes.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Generator, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.oe.guided_close import close_angles, close_step
from tooltransfer.planner.planning.oe.guided_field import UNREACHED, DistanceField, distance_field
from tooltransfer.planner.planning.oe.guided_holds import lattice_rules, straight_to
from tooltransfer.planner.planning.oe.guided_moves import (
    MAX_WINDOWS,
    REACH_SLACK,
    _Contact,
    _FaceMoves,
    _rolled,
    _step_of,
)
from tooltransfer.planner.planning.oe.guided_rungs import _ladder, _Rung
from tooltransfer.planner.planning.oe.metrics import plan_metrics
from tooltransfer.planner.planning.oe.piecewise import fit_runs
from tooltransfer.planner.planning.oe.push_plan import PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.qp_variant import condense_sequence
from tooltransfer.planner.planning.plan import Plan
from tooltransfer.planner.planning.setting import Setting


@dataclass(frozen=True)
class GuidedPath:
    """A path the search found: puck positions (K, 2) [m] (start first, target last) and the face
    that pushes along each step (K - 1,)."""

    xy: NDArray[np.float64]
    faces: tuple[str, ...]
    windows: tuple[tuple[float, float] | None, ...] = ()
    runs: tuple[int, ...] = ()

    def face_windows(self) -> dict[str, tuple[float, float]] | None:
        """The contact window [m] of each face whose steps keep to one (:func:`contact_windows`), or
        None where a face's steps use several (the path is then fitted run by run)."""
        out: dict[str, tuple[float, float] | None] = {}
        for face, w in zip(self.faces, self.windows or (None,) * len(self.faces), strict=True):
            if out.setdefault(face, w) != w:
                return None
        return {f: w for f, w in out.items() if w is not None}

    def sequence(self, duration: float) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[str, ...],
                                                  tuple[float, ...]]:
        """``(t, ref, faces, switches)``: times (K,) [s] in proportion to the length over ``duration``
        [s], the reference path (K, 2) [m], the runs' faces and the times of their changes [s]."""
        seg = np.hypot(*np.diff(self.xy, axis=0).T)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        t = duration * s / s[-1]
        faces, switches = [self.faces[0]], []
        for k in range(1, len(self.faces)):
            if self.faces[k] != faces[-1]:
                faces.append(self.faces[k])
                switches.append(float(t[k]))
        return t, self.xy, tuple(faces), tuple(switches)



@dataclass(frozen=True)
class GuidedMiss:
    """The search found no path: after ``expansions`` expansions of ``step`` [m], with every reachable
    lattice cell expanded (``exhausted``: no path under its rules at its resolution) or with its budget
    spent; ``unguided``: in the order of a distance field (:func:`guide_field`) that connects no way from
    the start to the target's funnel either."""

    expansions: int
    exhausted: bool
    step: float
    unguided: bool = False

    def describe(self) -> str:
        """One clause: what was searched and what remains."""
        field = (f"; its distance field found no way from the start to the target either (the search's faces and "
                 f"holds on {CELL * 1e3:g} mm cells, the contact's rolling left out)") if self.unguided else ""
        if self.exhausted:
            return (f"its space closed after {self.expansions} expansions (no path in {self.step * 1e3:g} mm steps "
                    f"under its rules; finer steps or other contact places may still find one{field})")
        return (f"no path within {self.expansions} expansions of {self.step * 1e3:g} mm steps (its budget, "
                f"oe.guided_budget{field})")


@dataclass(frozen=True)
class Refusal:
    """A change of face a later stage refused: from ``face_a`` to ``face_b`` with the object at
    ``where`` (2,) [m] (a switch with no admissible tool path round the object there)."""

    face_a: str
    face_b: str
    where: NDArray[np.float64]

    def near(self, came: str | None, face: str, p: NDArray[np.float64]) -> bool:
        """Whether changing from ``came`` to ``face`` at ``p`` (2,) [m] is this change, within
        :data:`REFUSED_RADIUS`."""
        return (came == self.face_a and face == self.face_b
                and math.hypot(float(p[0] - self.where[0]), float(p[1] - self.where[1])) < REFUSED_RADIUS)


#: Step [m] of the search's straight pushes.
STEP = 0.004
#: Side [m] of the lattice cells the search visits once per face.
CELL = 0.002
#: The finer attempt's share of :data:`STEP` and :data:`CELL` (narrow passages between an obstacle's
#: margin and the edge of a cone, where a whole step leaves the cone or enters the margin).
FINE = 0.5

#: How near [m] a refused change of face (:class:`Refusal`) the search no longer makes it.
REFUSED_RADIUS = 2 * STEP



def _backtrack(nodes: list, k: int, target: NDArray[np.float64], last: str, touch: _Contact,
               moves: dict[str, _FaceMoves]) -> GuidedPath:
    """The path of the search's node ``k`` (``nodes``: position, parent, face's key in ``moves``,
    contact) and its last step to ``target`` with the face of key ``last``, its contact ``touch``."""
    xy, fs, runs = [target], [last], [touch.run]
    while k >= 0:
        q, parent, face, contact = nodes[k]
        xy.append(q)
        if face is not None:
            fs.append(face)
            runs.append(contact.run)
        k = parent
    keys = fs[::-1]
    return GuidedPath(np.array(xy[::-1]), tuple(moves[f].name for f in keys), tuple(moves[f].window for f in keys),
                      tuple(runs[::-1]))



def guided_path(setting: Setting, start: NDArray[np.float64], target: NDArray[np.float64], *,
                options: QPOptions, step: float = STEP, cell: float = CELL, switch_price: float = 0.01,
                budget: int = 3000, refused: Sequence[Refusal] = (), windows: bool = False,
                more: bool = False, mixed: float | None = None, greed: float = 1.0,
                room: float = REACH_SLACK, guide: DistanceField | None = None,
                most: int = MAX_WINDOWS, close: bool = False) -> GuidedPath | GuidedMiss:
    """A* from ``start`` to within ``step`` of ``target`` (module docstring), or a :class:`GuidedMiss` within
    ``budget`` expansions. ``options``: the ``qp`` fit's (its narrowed friction cone, contact margin,
    span and most contacts per push); ``switch_price`` [m]: a face change's worth in path; ``refused``:
    changes it does not make; ``windows``: each face's runs keep their contact to one of its
    :func:`contact_windows` (a change of window is a re-contact, priced as a change of face); ``more``:
    half steps where a whole one rolls the contact off its face and a new run of a face where one
    outgrows ``oe.max_contacts`` contacts (:func:`~.guided_moves._step_of`); ``mixed`` [m]: each face
    as a whole and, where the whole is not held, its :func:`contact_windows` of that span (a way past an
    obstacle that only a contact toward one end of a face keeps the tool clear on, without multiplying
    the lattice where the whole face is held); ``greed`` (>= 1): the weight of the distance to go in the
    search's order (weighted A*: a path whose cost, length plus the price of its changes of face, is at
    most ``greed`` times the least on the lattice, found with far fewer expansions); ``room`` [m]: how far
    the tool outline keeps from the obstacles at the search's nodes (``mixed`` and ``windows`` are not
    taken together: their windows would share keys); ``guide``: the distance to go, instead of the
    straight line, a field of these faces and holds (:func:`guide_field`: a path round an obstacle that
    the straight line's order leaves unexpanded); ``most``: the most windows per face (odd); ``close``: the steps of the
    ladder's closest attempt (:func:`~.guided_close.close_step`: each ending where its face still holds the puck,
    shrunk where the whole would not, each on cells as much finer). A lattice cell is visited once per face (and
    window), with the contacts its first visit had used."""
    if windows and mixed is not None:
        raise ValueError("guided_path takes windows or mixed, not both")
    held, free, by_name = lattice_rules(setting, options, windows, mixed, room, most)

    def allowed(came: str | None, face: str, p: NDArray[np.float64]) -> bool:
        """Whether the change from ``came`` to ``face`` at ``p`` was not refused (``face`` "": a re-contact
        of ``came``)."""
        a, b = (by_name[came].name, by_name[face or came].name) if came is not None else ("", "")
        return came is None or came == face or not any(r.near(a, b, p) for r in refused)

    def finish(p: NDArray[np.float64], came: str | None, here: list[tuple[str, float, float]]) -> str | None:
        """A face that pushes the object from ``p`` straight to the target (within its cone at both
        ends of the step, held at both), if the target is within ``3 step``."""
        d = target - p
        if float(np.hypot(*d)) > 3 * step:
            return None
        return next((name for name in straight_to(math.atan2(d[1], d[0]), here, held(target, every=True))
                     if allowed(came, name, p)), None)

    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    to_go = guide.to_go if guide is not None else (lambda q: float(np.hypot(*(target - q))))
    heap: list = [(greed * to_go(start), 0.0, 0, None)]
    nodes: list[tuple[NDArray[np.float64], int, str | None, _Contact]] = [(start, -1, None, _Contact())]
    levels: dict[int, int] = {}  # the closest attempt's nodes at the end of a shrunk step: their level
    one_run_each = options.model_copy(update={"max_contacts": 1}) if close else options  # its re-contacts: new runs

    def cell_of(q: NDArray[np.float64], face: str | None, level: int) -> tuple:
        c = cell / 2 ** level
        return (int(q[0] // c), int(q[1] // c), face) + ((level,) if level else ())

    seen: set = set()
    n = 0
    while heap and n < budget:
        _, g, k, _ = heapq.heappop(heap)
        p, _, came, touch = nodes[k]
        key = cell_of(p, came, levels.get(k, 0))
        if key in seen:
            continue
        seen.add(key)
        n += 1
        here = held(p, came)
        last = finish(p, came, here)
        final = None if last is None else _rolled(setting, options, by_name[last], came, touch, p, target, more)
        if last is not None and final is not None:
            return _backtrack(nodes, k, target, last, final, by_name)
        for name, mid, half in here:
            if not allowed(came, name, p):
                continue
            for ang in close_angles(mid, half) if close else (mid - half, mid, mid + half):
                level = 0
                if close:
                    made = close_step(setting, one_run_each, by_name[name], came, touch, p, float(ang), half, step,
                                      free, lambda q, f: held.holds(by_name[f], q))
                    got, level = (None, 0) if made is None else (made[:2], made[2])
                else:
                    got = _step_of(setting, options, by_name[name], came, touch, p, ang, half, step, more)
                if got is None or not free(got[0]) or cell_of(got[0], name, level) in seen:
                    continue
                q, after = got
                if came == name and (after.count, after.run) != (touch.count, touch.run) and not allowed(name, "", p):
                    continue  # a re-contact of the face the later stages refused near here
                g2 = g + step / 2 ** level + (switch_price if came is not None and name != came else 0.0)
                nodes.append((q, k, name, after))
                if level:
                    levels[len(nodes) - 1] = level
                heapq.heappush(heap, (g2 + greed * to_go(q), g2, len(nodes) - 1, name))
    return GuidedMiss(n, not heap, step, guide is not None and guide.to_go(start) >= UNREACHED)


def guide_field(setting: Setting, start: NDArray[np.float64], target: NDArray[np.float64], *, options: QPOptions,
                step: float = STEP, windows: bool = False, mixed: float | None = None,
                room: float = REACH_SLACK) -> DistanceField:
    """The :func:`~.guided_field.distance_field` (cells of :data:`CELL`) of :func:`guided_path`'s faces and
    holds under these settings, its funnel the reach of its last straight push (``3 step`` [m]) from
    ``start`` to ``target`` (2,) [m]: its ``guide``, built once for the searches again after a refusal."""
    held, free, _ = lattice_rules(setting, options, windows, mixed, room)
    return distance_field(held, free, np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64),
                          3 * step, CELL)


def guided_plans(t: NDArray[np.float64], universal: NDArray[np.float64], setting: Setting,
                 target: NDArray[np.float64] | None, options: QPOptions) -> Generator[PushPlan, Any, None]:
    """The ``qp`` variant's fallback when its scored candidates fail: a ladder of attempts, each
    :func:`guided_path` at a share of the friction cone's half-angle: the task's
    ``options.friction_cone_fraction``; then :data:`~.guided_rungs.MIDDLE_SHARE` (where wider, and at most
    ``friction_cone_fraction_max``); then that share with half steps and new runs where the contact rolls
    off its face; then, where no attempt before could push from the start at all (the Omni may hold a face
    there only with its contact toward one end), that with each run's contact kept to one window of
    ``guided_contact_span`` of its face (where narrower than ``contact_span``); then that share on
    :data:`FINE` steps and cells; then (where ``guided_contact_span`` is narrower than ``contact_span``)
    at the middle share on fine steps with half steps and new runs, each face as a whole and, where the
    whole is not held, on its windows of ``guided_contact_span`` (``mixed``: a contact toward one end of a
    face where only there the tool clears an obstacle), the search weighted toward the target
    (:data:`~.guided_rungs.GREED`), the tool :data:`~.guided_rungs.LAST_ROOM` from the obstacles at its nodes, and
    :data:`~.guided_rungs.LAST_REFUSALS` searches again; last, where ``friction_cone_fraction_max`` is wider still (and
    widens some face's admissible cone: :func:`_widens`), that share on whole and on fine steps, then as
    the attempt before (plans at the edge of the cone, where nothing narrower was found: a task the
    certificate's whole cone cannot rule out); last of all (where ``guided_contact_span`` is narrower),
    the middle share's ``mixed`` attempt in the order of the distance to go over a grid of the faces' pushes
    (:mod:`~.guided_field`, ``guide``: a way round an obstacle that the straight line's order left
    unexpanded; whole faces hold the puck over longer runs, so its plans have fewer pushes and re-contacts),
    then that attempt on every face's windows (a way only the windows hold), both whether or not the attempts
    before could push from the start (the caller makes neither after a plan with little room); after them, where an
    attempt on whole steps and whole faces ended on its budget rather than with its space closed, the middle share's
    whole steps with half steps and new runs again, weighted toward the target (:data:`~.guided_rungs.GREED`) and
    searched again :data:`~.guided_rungs.LAST_REFUSALS` times (metric ``guided_spent``; not made after a plan with
    little room either); last (where ``guided_contact_span`` is narrower), the middle share's ``mixed`` attempt again
    on windows of a :data:`~.guided_rungs.NARROW` share of that span, :data:`~.guided_rungs.NARROW_WINDOWS` per face
    and :data:`~.guided_rungs.NARROW_BUDGET` times the expansions (a contact held only within a millimetre or two of
    one place on a face, where no window of the span is held at both of its ends; metric ``guided_narrow``); last of
    all, that attempt on windows of a :data:`~.guided_rungs.CLOSE` share, the tool :data:`~.guided_close.CLOSE_ROOM`
    from the obstacles, each step ending where its face still holds the puck (:mod:`~.guided_close`; metric
    ``guided_close``); neither is made after a plan with little room. The ``mixed`` attempts run also where the
    attempts before them could not push from the start (their windows may; the widest share's whole-face attempts do
    not), and after a plan with little room (the caller's ``GUIDED_ROOM``), which a roomier one may replace (the
    caller takes none at the widest share after a plan at a narrower one).
    Each attempt's sequence (found within ``options.guided_budget`` expansions, on fine
    steps ``1 / FINE`` times that: a path takes that many more steps) is fitted by
    :func:`condense_sequence` over the universal path's duration (``t`` (T,) [s], ``universal`` (T, 2)
    [m]) under that share. Yields each attempt's push plan, ``infeasible`` with the reason when the search
    or the fit fails; the caller stops at the first whose whole plan passes its checks. The share a plan
    used is its metric ``friction_cone_fraction``: plans keep the task's share whenever one exists.

    The caller may send back why a solved push plan failed later: a
    :class:`~tooltransfer.planner.planning.assemble.SwitchFailed` with the object's position (a switch
    with no tool path there) makes the search run again without that change of face near there (at
    most :data:`~.guided_rungs.REFUSALS` times per attempt, :data:`~.guided_rungs.LAST_REFUSALS` in the ``mixed``
    ones); a whole plan it keeps (a :class:`~tooltransfer.planner.planning.plan.Plan`: one with little room, kept
    unless a later attempt gives a roomier one) makes it skip the last attempts (``guide``, ``spent``,
    ``narrow``, ``close``); anything else, the next attempt."""
    target = universal[-1] if target is None else target
    tries = _ladder(setting, options)
    stuck = True  # every attempt so far on whole-face contacts could not push from the start at all
    kept = False  # the caller keeps a whole plan of an attempt before
    on_budget = False  # an attempt on whole steps and whole faces ended on its budget
    for rung in tries:
        if rung.last and kept:
            continue  # after a plan kept with little room: the last attempts are for tasks with no plan at all
        if rung.spent and not on_budget:
            continue
        if not rung.guide and ((rung.windows and not stuck)
                               or (stuck and rung.mixed is None and (rung.fine or rung.widest))):
            continue  # (which faces hold the puck at the start depends on neither; their steps' directions
            # do a little on the share, so a face held there but stepping nowhere at 0.8 is not tried wider;
            # the field's order runs on every face's windows whether or not those before could push from it)
        opts = options.model_copy(update=rung.change)
        order = guide_field(setting, universal[0], target, options=opts, step=FINE * STEP if rung.fine else STEP,
                            windows=rung.windows, mixed=rung.mixed, room=rung.room) if rung.guide else None
        refused: list[Refusal] = []
        for _ in range(1 + rung.refusals):
            plan = _attempt(t, setting, target, opts, universal, refused, rung, order)
            stuck = stuck and (not rung.whole_faces or plan.metrics.get("guided_expansions") == 1.0)
            on_budget = on_budget or (rung.whole_faces and not rung.fine
                                      and plan.metrics.get("guided_on_budget") == 1.0)
            failed = yield plan
            kept = kept or isinstance(failed, Plan)
            where = getattr(failed, "where", None)
            if plan.status != "solved" or where is None:
                break
            refused.append(Refusal(failed.face_a, failed.face_b, where))


def _attempt(t: NDArray[np.float64], setting: Setting, target: NDArray[np.float64], opts: QPOptions,
             universal: NDArray[np.float64], refused: list[Refusal], rung: _Rung,
             order: DistanceField | None = None) -> PushPlan:
    """One attempt of :func:`guided_plans` at the share of ``opts``, without the ``refused`` changes, on
    the search's settings of ``rung`` (:class:`_Rung`), in the order of ``order`` where given."""
    share, fine, mixed = opts.friction_cone_fraction, rung.fine, rung.mixed
    budget = opts.guided_budget * rung.scale
    found = guided_path(setting, universal[0], target, options=opts, refused=refused, windows=rung.windows,
                        more=rung.more, mixed=mixed, greed=rung.greed, room=rung.room, guide=order, most=rung.most,
                        close=rung.close,
                        **({"step": FINE * STEP, "cell": FINE * CELL, "budget": round(budget / FINE)}
                           if fine else {"budget": budget}))
    but = f" without the {len(refused)} change(s) of face refused," if refused else ""
    close = (f", each step ending where its face holds, the tool {rung.room * 1e3:g} mm from obstacles"
             if rung.close else "")
    on = (f" (the contact on {opts.contact_span * 1e3:g} mm{' windows' if rung.windows else ''} of each face"
          f"{f' or, where that is not held, on its {mixed * 1e3:g} mm windows' if mixed is not None else ''}"
          f"{', half steps and new runs where it rolls off' if rung.more else ''}"
          f"{f', the distance to go weighted {rung.greed:g}' if rung.greed != 1.0 else ''}"
          f"{', that distance over a grid of where the faces push' if rung.guide else ''}"
          f"{', again after a search on whole steps spent its budget' if rung.spent else ''}"
          f"{close})")
    if isinstance(found, GuidedMiss):
        empty = np.zeros((0, 2))
        return PushPlan("qp", "infeasible", np.zeros(0), empty, empty, universal,
                        reason=f"at {share:g} of the friction cone{on},{but} {found.describe()}",
                        metrics={"guided_expansions": float(found.expansions),
                                 "guided_on_budget": 0.0 if found.exhausted else 1.0})
    tg, ref, faces, switches = found.sequence(float(t[-1] - t[0]))
    kept = found.face_windows()  # None: a face's runs keep to different windows, fitted run by run only
    plan = condense_sequence(tg + t[0], ref, setting, target, faces, tuple(v + t[0] for v in switches),
                             opts.model_copy(update={"contact_windows": kept}) if kept else opts) \
        if kept is not None else PushPlan("qp", "infeasible", np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)), ref,
                                          reason="a face's runs keep their contact to different windows")
    if plan.status != "solved":  # one fit per run of a face, the object at rest between them
        runs = fit_runs(found.xy, found.faces, tg + t[0], setting, opts, found.windows, found.runs)
        plan = runs if runs.status == "solved" else replace(
            plan, reason=f"at {share:g} of the friction cone{on},{but} a path of {len(found.faces)} steps of "
                         f"{(FINE if fine else 1.0) * STEP * 1e3:g} mm, not fitted: {plan.reason}; {runs.reason}")
    if plan.status == "solved":  # measured like every plan of the variant, at the share it used
        frames = {f.name: FaceFrame.build(setting, f.name, friction_cone_fraction=share) for f in setting.tool.faces
                  if f.name in faces}
        plan.metrics.update(plan_metrics(plan, frames, target, setting), friction_cone_fraction=share,
                            guided_step=FINE * STEP if fine else STEP)
    # where the plan came from: the widest share (the caller keeps a plan with little room of a narrower share
    # rather than this), the distance field's order, the weighted search made again after one spent its budget,
    # the narrow windows
    plan.metrics.update({metric: 1.0 for metric, made in (("guided_widest", rung.widest), ("guided_field", rung.guide),
                                                          ("guided_spent", rung.spent), ("guided_narrow", rung.narrow),
                                                          ("guided_close", rung.close))
                         if made})
    return plan
