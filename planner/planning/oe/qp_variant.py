"""The ``qp`` variant of OE condensing (this project, docs/design.md section 5 step 5).

For a new tool, the generalized universal object path is condensed into pushes the tool can make
on the Omni. A candidate push sequence (faces in order, switch times) is scored by the constrained
DMP fit of :mod:`tooltransfer.dmp.qp`: track the universal path, with, during each push, the object's velocity in
the active face's admissible cone (its friction cone about the normal, narrowed to the options'
``friction_cone_fraction`` and intersected with the tool file's cone, turning with the tool heading, re-linearised
until it settles; :mod:`tooltransfer.planner.planning.oe.face_frame`), the contact on the face's usable segment as it
rolls (:class:`tooltransfer.planner.planning.oe.constraints.ContactOnFace`), the object where the Omni can push it from
with that face wherever the contact is on it (:func:`tooltransfer.planner.planning.oe.constraints.reach_constraints` at
both ends of the segment), obstacles kept out with the setting's margin beyond its radius, and the
target reached with zero velocity. At a switch instant
both faces' rows hold, so the object stops there when their cones do not overlap (the tool moves
round it while it stands still). Cost: the fit's objective (half the mean squared deviation from
the universal path [m^2]) plus ``switch_price`` per face change.

Search (:func:`condense_qp`), bounded and pruned, not exhaustive:

1. pre-checks: the start and the target must each be in reach of some face (else ``infeasible``);
2. every face order of at most ``max_pushes`` pushes is ranked by a proxy
   (:mod:`tooltransfer.planner.planning.oe.sequence_proxy`) with switch times on a grid of ``segments`` equal phases;
3. the ``candidates`` best are scored by the QP (one sequential-convex solve each) on a coarser
   screening grid;
4. the best feasible one has each switch moved by one segment either way, kept when it lowers
   the cost (one pass);
5. the cheapest screened candidates are solved again on the full grid; the first feasible one
   whose pushes the inverse push model realises (:mod:`tooltransfer.planner.planning.oe.contacts`: tool poses, the
   contact's start, re-contacts where one contact cannot carry the travel) is the plan.

What it guarantees: the returned plan satisfies every constraint family on the dense grid (the
measured violations are in its metrics), and it is the cheapest of the sequences scored; it does
not guarantee the global optimum over all sequences and switch times. ``infeasible`` means the
pre-checks failed or no scored candidate was feasible; the reason names which and why.

The options are :class:`tooltransfer.planner.planning.oe.qp_options.QPOptions`; one candidate's fit and cost are
:class:`tooltransfer.planner.planning.oe.sequence_fit.SequenceFit`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.planning.oe.constraints import HeadingCone, OffsetSeries, realised_offsets
from tooltransfer.planner.planning.oe.contacts import PushRefused, realise_pushes
from tooltransfer.planner.planning.oe.metrics import CONE_BOUND, SPEED_TOL, heading_cone_violation
from tooltransfer.planner.planning.oe.push_plan import Push, PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.sequence_fit import ScoredSequence, SequenceFit
from tooltransfer.planner.planning.oe.sequence_proxy import ranked_sequences, reach_distance, segment_costs
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.validation import check_array

FINAL_TRIES = 3
"""Screened candidates solved on the full grid, in order of cost, before the search gives up."""

HEADING_TOL = 0.005
"""Angle [rad] by which a realised push may leave its cone at the tool's real heading before the fit is
written again at the realised contacts (:func:`_realised`); half the plan's hard bound."""

HEADING_ROUNDS = 3
"""Fits with the cone at the realised contacts at most (:func:`_realised`: the realisation that leaves its
cones least is kept, and refused when that is by more than :data:`~.metrics.CONE_BOUND`)."""


class ConeRefused(PushRefused):
    """A path whose every realisation leaves its cones at the tool's real heading by more than the hard
    bound; ``fits``: the fits made again at the realised contacts (they count among the fits spent)."""

    def __init__(self, message: str, fits: list[ScoredSequence]) -> None:
        super().__init__(message)
        self.fits = fits

SCREEN_RTOL = 1e-3
"""Relative objective change at which a screening fit stops re-linearising (the ranking is not
changed by the last per-mille; the final fit runs to ``QPOptions.scp_rtol``)."""


def _precheck(fit: SequenceFit, check_start: bool = True) -> str:
    ends = np.vstack([fit.universal[0], fit.target])
    reach = {f: reach_distance(fr, ends) for f, fr in fit.frames.items()}
    for i, what in ((0, "start"), (1, "target")):
        if (i or check_start) and all(r[i] > 0 for r in reach.values()):
            gap = min(r[i] for r in reach.values())
            return f"{what} outside the Omni's reach for every face (nearest face {gap * 1e3:.1f} mm away)"
    return ""


def _pushes(fit: SequenceFit, best: ScoredSequence, t: NDArray[np.float64], x: NDArray[np.float64],
            s_first: float | None = None, spans_wanted: int | None = None) -> tuple[Push, ...]:
    """The pushes of the fitted path (of its first ``spans_wanted`` faces), realised by the inverse
    push model (raises PushRefused)."""
    edges = (t[0], *best.switches, t[-1])
    spans = [(face, np.flatnonzero((t >= lo - 1e-12) & (t <= hi + 1e-12)))
             for face, lo, hi in zip(best.faces, edges[:-1], edges[1:], strict=True)]
    pushes = realise_pushes(fit.setting, spans[:spans_wanted], t, x, fit.opts, s_first)
    if fit.free_start:  # the fit's reach rows started late: the realised tool poses, exactly
        from tooltransfer.tools.omni.ik import joint_path

        for p in pushes:
            jp = joint_path(fit.platform, p.tool_pose[:, :2])
            bad = np.flatnonzero(jp.refused)
            if bad.size:
                where = np.round(p.tool_pose[bad[0], :2], 4).tolist()
                raise PushRefused(f"face {p.face!r} would hold the tool at {where} m, outside the Omni's reach "
                                  "or joint limits")
    return pushes


def _span_offsets(fit: SequenceFit, best: ScoredSequence, pushes: tuple[Push, ...]) -> dict[int, list[OffsetSeries]]:
    """For each face span of ``best`` (by index), one series per realised push in it (re-contacts their
    own): its times [s] and the object's offsets [m] from the arm's plane, its contact where it was on
    ``best``'s path."""
    roll = best.result.rollout
    assert roll is not None
    edges = (roll.t[0], *best.switches, roll.t[-1])
    out: dict[int, list[OffsetSeries]] = {}
    for n, (face, lo, hi) in enumerate(zip(best.faces, edges[:-1], edges[1:], strict=True)):
        for p in pushes:
            if p.face == face and p.t_start >= lo - 1e-9 and p.t_end <= hi + 1e-9 and len(p.samples) >= 2:
                off = realised_offsets(fit.frames[face].base, roll.x[p.samples], p.tool_pose[:, 2])
                out.setdefault(n, []).append((roll.t[p.samples], off))
    return out


def _cone_worst(fit: SequenceFit, best: ScoredSequence, pushes: tuple[Push, ...]) -> float:
    """The largest angle [rad] by which ``pushes`` leave their cones at their own poses' heading."""
    roll = best.result.rollout
    assert roll is not None
    return max((heading_cone_violation(fit.frames[p.face], p, roll.x[p.samples], roll.v[p.samples], SPEED_TOL)
                for p in pushes), default=0.0)


def _realised(fit: SequenceFit, best: ScoredSequence, s_first: float | None = None,
              spans_wanted: int | None = None) -> tuple[ScoredSequence, tuple[Push, ...], list[ScoredSequence]]:
    """``best``'s fitted path realised (:func:`_pushes`), with the cone rows re-written at the tool's
    real heading until the path keeps its cones there.

    The fit writes each face's cone in the frame of one contact place; the realised contact rolls
    along the face, and where it is moves the object's offset from the arm's plane, hence the tool's
    heading, by up to degrees on a long face. Where a push leaves its cone at the realised heading by
    more than :data:`HEADING_TOL`, the sequence is fitted again, warm-started at the path, with the
    rows inside the cones at the headings of every realised push so far
    (:class:`~.constraints.HeadingCone` ``offsets``), and realised again: at most
    :data:`HEADING_ROUNDS` times. The realisation that leaves its cones least is kept.

    Returns:
        the kept fit, its pushes, and the fits made again (for the count of fits).
    Raises:
        ConeRefused: no realisation keeps its cones within the plan's hard bound
            (:data:`~.metrics.CONE_BOUND`); it carries the fits made again.
        PushRefused: the first realisation fails (:func:`_pushes`).
    """
    assert best.result.rollout is not None
    pushes = _pushes(fit, best, best.result.rollout.t, best.result.rollout.x, s_first, spans_wanted)
    worst = _cone_worst(fit, best, pushes)
    kept, again_fits, why = (worst, best, pushes), [], ""
    seen: dict[int, list[OffsetSeries]] = {}
    for _ in range(HEADING_ROUNDS):
        if kept[0] <= HEADING_TOL:
            break
        roll = best.result.rollout
        for k, series in _span_offsets(fit, best, pushes).items():
            seen.setdefault(k, []).extend(series)
        problem = fit.problem(best.faces, best.switches, seen)
        if any(c.empty(roll.t, roll.x) for c in problem.constraints if isinstance(c, HeadingCone)):
            why = "the cones at the realised contacts do not overlap"
            break
        again = fit.score(best.faces, best.switches, offsets=seen, start=(roll.t, roll.x), problem=problem)
        again_fits.append(again)
        if not again.feasible or again.result.rollout is None:
            why = "its fit with the cone at the realised contacts is infeasible"
            break
        try:
            pushes = _pushes(fit, again, again.result.rollout.t, again.result.rollout.x, s_first, spans_wanted)
        except PushRefused as exc:
            why = f"its fit with the cone at the realised contacts cannot be realised ({exc})"
            break
        best = again
        worst = _cone_worst(fit, best, pushes)
        if worst < kept[0]:
            kept = (worst, best, pushes)
    if kept[0] > CONE_BOUND:
        tail = f"; {why}" if why else ""
        raise ConeRefused(f"the path leaves its cone by {kept[0]:.3f} rad at the tool's real heading after "
                          f"{len(again_fits)} fit(s) with the cone at the realised contacts{tail}", again_fits)
    return kept[1], kept[2], again_fits


def _refits(exc: PushRefused) -> list[ScoredSequence]:
    """The fits a refused realisation made again at the realised contacts (they count among the fits spent)."""
    return exc.fits if isinstance(exc, ConeRefused) else []


def condense_sequence(
    t: NDArray[np.float64], universal: NDArray[np.float64], setting: Setting,
    target: NDArray[np.float64], faces: tuple[str, ...], switches: tuple[float, ...],
    options: QPOptions | None = None, *, s_first: float | None = None, first_face_only: bool = False,
    free_start: bool = False,
) -> PushPlan:
    """One push sequence (``faces`` with switches at times ``switches`` [s]) fitted to the path
    ``universal`` (T, 2) [m] on times ``t`` (T,) [s] and realised, without the search: the closed
    loop's re-plan of the rest of a task from the observed object (``universal`` then runs from it).
    The fit's non-convex rows are first linearised at ``universal`` (warm-started from the plan in
    force, when that is what it is). ``s_first`` [m]: where the first face already touches the
    object; ``first_face_only``: realise only the first face's pushes (what a receding horizon
    executes before it re-plans; the pushes then end before the path does); ``free_start``: the
    first face's reach rows apply from where the path enters them (an object observed off the plan
    may start outside the region every contact on the face reaches it from), the realised tool poses
    then checked exactly. ``infeasible`` with the reason when the fit or the realisation fails."""
    start_time = time.perf_counter()
    opts = options or QPOptions()
    t = check_array(t, "t", ndim=1)
    universal = check_array(universal, "universal", shape=(t.size, 2))
    target = check_array(target, "target", shape=(2,))
    grid = np.linspace(t[0], t[-1], opts.n_samples)
    ref = np.column_stack([np.interp(grid, t, universal[:, j]) for j in range(2)])
    fine = SequenceFit(grid, ref, setting, target, opts, free_start)
    empty = np.zeros((0, 2))
    s = fine.score(tuple(faces), tuple(float(v) for v in switches), warm=True)
    if not s.feasible or s.result.rollout is None:
        fams = ", ".join(s.result.families or tuple(k for k, v in s.result.violations.items() if v > opts.tol))
        return PushPlan("qp", "infeasible", np.zeros(0), empty, empty, ref, n_qp=s.result.scp_iterations,
                        reason=f"the sequence {' -> '.join(faces)} is infeasible from here ({fams or 'unknown'})",
                        metrics={"compute_time": time.perf_counter() - start_time})
    try:
        kept, pushes, again = _realised(fine, s, s_first, 1 if first_face_only else None)
    except PushRefused as exc:
        spent = s.result.scp_iterations + sum(a.result.scp_iterations for a in _refits(exc))
        return PushPlan("qp", "infeasible", np.zeros(0), empty, empty, ref, reason=str(exc), n_qp=spent,
                        metrics={"compute_time": time.perf_counter() - start_time})
    roll = kept.result.rollout
    assert roll is not None
    n_qp = s.result.scp_iterations + sum(a.result.scp_iterations for a in again)
    return PushPlan("qp", "solved", roll.t, roll.x, roll.v, ref, pushes=pushes, n_qp=n_qp,
                    metrics={"compute_time": time.perf_counter() - start_time})


def _infeasible(ref: NDArray[np.float64], start_time: float, reason: str, n_qp: int = 0, cands: tuple = ()) -> PushPlan:
    """The plan when no push sequence works, with the ``reason``, the fits spent and the candidates
    scored; ``ref`` the resampled universal path, ``start_time`` the condensation's start [s]."""
    empty = np.zeros((0, 2))
    return PushPlan("qp", "infeasible", np.zeros(0), empty, empty, ref, reason=reason, n_qp=n_qp,
                    candidates=cands, metrics={"compute_time": time.perf_counter() - start_time})


def _screened(screen: SequenceFit, grid: NDArray[np.float64], opts: QPOptions) -> list[ScoredSequence]:
    """Every candidate scored on the screening grid: the best-ranked push sequences of the proxy
    costs (switches at segment bounds), then the best feasible one's switches moved one segment
    either way while that lowers its cost (a local search on the cuts)."""
    v_ref = np.gradient(screen.universal, screen.t, axis=0)
    names = list(screen.frames)
    frames = [screen.frames[n] for n in names]
    costs = segment_costs(screen.t, screen.universal, v_ref, frames, opts.segments)
    bounds = np.linspace(grid[0], grid[-1], opts.segments + 1)
    ranked = ranked_sequences(costs, names, opts.max_pushes, opts.switch_price)[: opts.candidates]
    scored = [screen.score(faces, tuple(float(bounds[c]) for c in cuts), contact_rows=False)
              for faces, cuts, _ in ranked]
    feasible = [s for s in scored if s.feasible]
    if feasible:
        best = min(feasible, key=screen.cost)
        cuts = [int(np.argmin(np.abs(bounds - s))) for s in best.switches]
        for i in range(len(cuts)):
            for step in (-1, 1):
                trial = list(cuts)
                trial[i] += step
                lo = trial[i - 1] if i > 0 else 0
                hi = trial[i + 1] if i + 1 < len(trial) else opts.segments
                if not lo < trial[i] < hi:
                    continue
                s = screen.score(best.faces, tuple(float(bounds[c]) for c in trial), contact_rows=False)
                scored.append(s)
                if screen.cost(s) < screen.cost(best):
                    best, cuts = s, trial
    return scored


@dataclass
class _Finals:
    """The final stage of one condensation: the candidates the screening grid ranked (``order``)
    are solved again on the full grid (``fine``), in order; the first feasible one that the push
    model realises is the plan, which can hand out the next one (``PushPlan.next_best``) when a
    later stage (a switch) fails on it. ``scored`` gathers every fit, screening and final."""

    screen: SequenceFit
    fine: SequenceFit
    scored: list[ScoredSequence]
    order: list[ScoredSequence]
    grid: NDArray[np.float64]
    ref: NDArray[np.float64]
    target: NDArray[np.float64]
    setting: Setting
    opts: QPOptions
    start_time: float

    def _spent(self) -> tuple[int, tuple]:
        """The fits spent so far and the candidates scored (faces, switches, cost or None)."""
        n_qp = sum(sc.result.scp_iterations for sc in self.scored)
        cands = tuple((sc.faces, sc.switches, None if not sc.feasible else self.screen.cost(sc)) for sc in self.scored)
        return n_qp, cands

    def finalise(self, start: int, tried: int) -> PushPlan:
        """The plan from the candidates ``order[start:]`` (at most ``FINAL_TRIES`` of them), after
        ``tried`` final fits; infeasible with the reason when none works."""
        why = ""
        for i in range(start, min(len(self.order), start + FINAL_TRIES)):
            s = self.order[i]
            final = self.fine.score(s.faces, s.switches)
            self.scored.append(final)
            if not final.feasible or final.result.rollout is None:
                continue
            try:
                final, pushes, again = _realised(self.fine, final)
            except PushRefused as exc:
                self.scored += _refits(exc)
                why = f"the push sequence {' -> '.join(final.faces)} cannot be realised: {exc}"
                continue
            self.scored += again  # fitted again with the cone at the realised contacts
            roll = final.result.rollout
            assert roll is not None
            return self._solved(final, roll.t, roll.x, roll.v, pushes, i + 1, tried + i + 1 - start)
        n_qp, cands = self._spent()
        if why:
            return _infeasible(self.ref, self.start_time, why, n_qp, cands)
        fams = sorted({f for sc in self.scored for f in (sc.result.families or tuple(
            k for k, val in sc.result.violations.items() if val > self.opts.tol))})
        return _infeasible(
            self.ref, self.start_time,
            f"none of the {len(self.scored)} push sequences scored is feasible "
            f"(constraint families in conflict: {', '.join(fams) or 'unknown'})", n_qp, cands,
        )

    def _solved(self, best: ScoredSequence, dense_t: NDArray[np.float64], x: NDArray[np.float64],
                v: NDArray[np.float64], pushes: tuple[Push, ...], after: int, tried: int) -> PushPlan:
        """The solved plan of ``best`` (dense path ``x`` [m], ``v`` [m/s] at ``dense_t`` [s]) with its
        metrics; ``after``: the next candidate's index, ``tried``: final fits so far."""
        n_qp, cands = self._spent()
        plan = PushPlan("qp", "solved", dense_t, x, v, self.ref, pushes=pushes, n_qp=n_qp, candidates=cands)
        from tooltransfer.planner.planning.oe.metrics import plan_metrics  # local: metrics import the plan types

        metrics = plan_metrics(plan, self.fine.frames, self.target, self.setting)
        metrics["compute_time"] = time.perf_counter() - self.start_time
        metrics.update({f"violation_{k}": val for k, val in best.result.violations.items()})
        per_qp = [sc.result.solve_time / max(sc.result.scp_iterations, 1) for sc in self.scored]
        metrics.update({"n_qp": float(n_qp), "qp_time_median": float(np.median(per_qp)),
                        "qp_time_max": max(per_qp), "final_candidates": float(tried)})
        more = after < len(self.order) and tried < self.opts.alternatives + FINAL_TRIES
        return PushPlan("qp", "solved", dense_t, x, v, self.ref, pushes=pushes, metrics=metrics, n_qp=n_qp,
                        candidates=cands, next_best=(lambda: self.finalise(after, tried)) if more else None)


def condense_qp(
    t: NDArray[np.float64],
    universal: NDArray[np.float64],
    setting: Setting,
    target: NDArray[np.float64] | None = None,
    options: QPOptions | None = None,
    *,
    free_start: bool = False,
) -> PushPlan:
    """Condense the generalized universal path for ``setting``'s tool on its Omni (the ``qp`` variant).

    Args:
        t: times (T,) [s] of the generalized universal path, increasing.
        universal: the path (T, 2) [m]; it starts at the object's start.
        setting: the world: the new tool, the Omni carrying it, the object (radius, push
            mechanics), the obstacles (discs and convex shapely polygons, kept ``setting.margin``
            away from beyond the radius).
        target: where the object must end [m] (default the path's end).
        free_start: each candidate's first reach rows apply from where the path enters them (the
            closed loop's re-plan from an observed object, :func:`condense_sequence`).
    Returns:
        a :class:`PushPlan` (``status == "infeasible"`` with the reason when no plan is found).
    """
    start_time = time.perf_counter()
    opts = options or QPOptions()
    t = check_array(t, "t", ndim=1)
    universal = check_array(universal, "universal", shape=(t.size, 2))
    target = universal[-1] if target is None else check_array(target, "target", shape=(2,))
    def resample(n: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        g = np.linspace(t[0], t[-1], n)
        return g, np.column_stack([np.interp(g, t, universal[:, j]) for j in range(2)])

    grid, ref = resample(opts.n_samples)
    if not isinstance(setting, Setting):
        raise InputError("setting", "a tooltransfer.planner.planning.setting.Setting", type(setting).__name__)
    fine = SequenceFit(grid, ref, setting, target, opts, free_start)
    # ranking needs no 1e-8 accuracy: the screening fits stop at 1e-5 (the final one at ``tol``)
    screen_opts = opts.model_copy(update={"tol": max(opts.tol, 1e-5), "accept": max(opts.accept, 1e-5),
                                          "scp_rtol": max(opts.scp_rtol, SCREEN_RTOL)})
    screen = SequenceFit(*resample(min(opts.screen_samples, opts.n_samples)), setting, target, screen_opts,
                       free_start)

    why = _precheck(screen, check_start=not free_start)
    if why:
        return _infeasible(ref, start_time, why)
    scored = _screened(screen, grid, opts)
    # the screening grid ranked the candidates: the best ones are solved again on the full grid, in order
    order = sorted({(s.faces, s.switches): s for s in scored if s.feasible}.values(), key=screen.cost)
    return _Finals(screen, fine, scored, order, grid, ref, target, setting, opts, start_time).finalise(0, 0)
