"""The constrained DMP fit of one push sequence, and its cost, for the ``qp`` variant
(:mod:`tooltransfer.planner.planning.oe.qp_variant`).

:class:`SequenceFit` holds what is fixed while the search scores candidates (the grid, the universal path, the
world, the face frames, the obstacle rows) and builds one candidate's :class:`tooltransfer.dmp.qp.FitProblem`:
each push's heading cone, reach rows at both ends of the face's usable segment and contact rows, the end
conditions and the obstacles. :meth:`SequenceFit.score` fits it (first without the contact rows) and
:meth:`SequenceFit.cost` prices it: half the mean squared deviation [m^2], the face changes, the re-contacts.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp import DMP
from tooltransfer.dmp.qp import (
    FitProblem,
    FitResult,
    FixedEndPoint,
    OutsideDisc,
    OutsidePolygon,
    Ridge,
    TrackPath,
    ZeroEndVelocity,
    solve_fit,
)
from tooltransfer.dmp.qp.constraints.base import Constraint
from tooltransfer.planner.planning.oe.constraints import (
    ContactOnFace,
    HeadingCone,
    OffsetSeries,
    reach_constraints,
    reach_entry,
)
from tooltransfer.planner.planning.oe.contacts import usable_range
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.planner.planning.oe.objectives import RollingPenalty
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.setting import Setting
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.pushing.inverse import FaceGeometry

__all__ = ["ScoredSequence", "SequenceFit"]


@dataclass(frozen=True)
class ScoredSequence:
    """One candidate push sequence (``faces`` in order, switch times ``switches`` [s]) and its fit;
    feasible when the fit solved, or nearly did with every violation within ``accept`` [m, m/s]."""

    faces: tuple[str, ...]
    switches: tuple[float, ...]
    result: FitResult

    accept: float
    contacts: int = 0
    """contacts the pushes of the fitted path need (one per push plus the re-contacts)."""
    excess: float = 0.0
    """contact travel [m] beyond what ``max_contacts`` contacts per push carry (screening fits)."""

    @property
    def feasible(self) -> bool:
        r = self.result
        return r.status == "solved" or (r.status == "inaccurate" and max(r.violations.values()) <= self.accept)


def fit_frame(setting: Setting, face: str, opts: QPOptions) -> FaceFrame:
    """The frame ``face``'s cone rows are written in (at ``opts``' share of the friction cone): with its
    contact at the middle of the face's contact range or, where ``opts.contact_windows`` keeps the
    contact to a window of the face, at the middle of that window. The tool's heading, hence the
    admissible directions in the world, follows the contact's place: toward one end of a long face it
    turns by degrees (the guided search's steps on a window are inside that window's cone). The frame's
    ``s`` is that contact's arc length [m] (:attr:`~.push_plan.Push.frame_s` of the pushes fitted in it)."""
    cone = opts.friction_cone_fraction
    if face not in (opts.contact_windows or {}):
        return FaceFrame.build(setting, face, friction_cone_fraction=cone)
    lo, hi = usable_range(setting.tool, face, opts)
    return FaceFrame.build(setting, face, s=0.5 * (lo + hi) / setting.tool.face(face).length,
                           friction_cone_fraction=cone)


class SequenceFit:
    """Everything fixed while candidates are scored."""

    def __init__(
        self, t: NDArray[np.float64], universal: NDArray[np.float64], setting: Setting,
        target: NDArray[np.float64], opts: QPOptions, free_start: bool = False,
    ) -> None:
        self.t, self.universal, self.target, self.opts, self.setting = t, universal, target, opts, setting
        self.free_start = free_start
        tool = self.tool = setting.tool
        self.platform = setting.platform
        cone = opts.friction_cone_fraction
        self.frames = {f: fit_frame(setting, f, opts) for f in tool.face_names}
        self._face_rows: dict[str, tuple[FaceGeometry, tuple[float, float], list[FaceFrame]]] = {}
        for f in tool.face_names:
            g = FaceGeometry.of(tool, f)
            lo, hi = usable_range(tool, f, opts)
            ends = [FaceFrame.build(setting, f, s=s / g.length, friction_cone_fraction=cone) for s in sorted({lo, hi})]
            self._face_rows[f] = (g, (lo, hi), ends)
        self.dmp = DMP(2, n_basis=opts.n_basis)
        self.fixed: list[Constraint] = [FixedEndPoint(target), ZeroEndVelocity()]
        grow = setting.radius + setting.margin
        for o in setting.obstacles:
            if isinstance(o, Disc):
                self.fixed.append(OutsideDisc(o.centre, o.radius + grow, family="obstacle"))
            else:
                ring = np.asarray(o.exterior.coords)[:-1]
                self.fixed.append(OutsidePolygon(ring, grow, family="obstacle"))
        self._const: float | None = None
        self._reach: dict[tuple[str, float, float, bool], list[Constraint]] = {}  # :meth:`_reach_rows`

    def problem(self, faces: tuple[str, ...], switches: tuple[float, ...],
                offsets: Mapping[int, Sequence[OffsetSeries]] | None = None) -> FitProblem:
        """The candidate's fit problem; ``offsets``: for the pushes (by index) whose cone rows follow
        realised contacts, the times [s] and the object's offsets [m] from the arm's plane of each
        (:class:`~.constraints.HeadingCone`)."""
        edges = (self.t[0], *switches, self.t[-1])
        cons = list(self.fixed)
        for n, (face, lo, hi) in enumerate(zip(faces, edges[:-1], edges[1:], strict=True)):
            fr = self.frames[face]
            g, (s_lo, s_hi), _ = self._face_rows[face]
            cons.append(HeadingCone(fr, window=(lo, hi), offsets=(offsets or {}).get(n, ())))
            cons += self._reach_rows(face, lo, hi, first=n == 0)
            if s_hi > s_lo:
                cons.append(ContactOnFace(fr, g, self.setting.mechanics, self.setting.radius, s_lo, s_hi,
                                          max_contacts=self.opts.max_contacts, window=(lo, hi)))
        objectives: list = [TrackPath(self.universal)]
        if self.opts.ridge > 0:
            objectives.append(Ridge(self.opts.ridge))
        if self.opts.recontact_price > 0:
            objectives.append(RollingPenalty(
                [(self._face_rows[f][0], self.frames[f], lo, hi, self._face_rows[f][1])
                 for f, lo, hi in zip(faces, edges[:-1], edges[1:], strict=True)],
                self.universal, self.setting, self.opts.recontact_price))
        return FitProblem(self.dmp, self.t, x0=self.universal[0], g=self.target, objectives=objectives,
                          constraints=cons)

    def _reach_rows(self, face: str, lo: float, hi: float, first: bool) -> list[Constraint]:
        """The reach rows of a push of ``face`` over the window ``[lo, hi]`` [s]: at both ends of its usable
        segment (the Omni reaches the tool wherever the contact is on the face), in a re-plan's first
        window from where the reference enters them (:meth:`_entry`). Built once per window and shared by
        the candidates' problems, as the obstacles' rows are (these rows keep no state)."""
        key = (face, lo, hi, self.free_start and first)
        if key not in self._reach:
            fr, ends = self.frames[face], self._face_rows[face][2]
            ref = self.universal[(self.t >= lo - 1e-12) & (self.t <= hi + 1e-12)] - fr.base
            ang = np.arctan2(ref[:, 1], ref[:, 0])
            near = (float(ang.min()), float(ang.max())) if ang.size else None
            out: list[Constraint] = []
            for end in ends:
                rows = reach_constraints(end, window=(lo, hi), near=near)
                if key[3]:
                    start = self._entry(rows, lo, hi)
                    rows = rows if start == lo else reach_constraints(end, window=(start, hi), near=near)
                out += rows
            self._reach[key] = out
        return self._reach[key]

    def _entry(self, rows: list[Constraint], lo: float, hi: float) -> float:
        """When one contact end's reach ``rows`` start to apply in a re-plan's first window
        ``[lo, hi]`` [s]: where the reference first satisfies them. A re-plan starts where the object
        is, possibly outside the region every contact on the face reaches it from though inside the
        one the actual contact does (the realised tool poses are then checked against the joint
        limits exactly, :func:`~tooltransfer.planner.planning.oe.qp_variant.condense_sequence`); ``lo`` when the
        reference starts inside or never enters."""
        inside = np.flatnonzero((self.t >= lo - 1e-12) & (self.t <= hi + 1e-12))
        k = reach_entry(rows, self.universal[inside])
        return lo if k == 0 or k >= inside.size else float(self.t[inside[k]])

    def score(self, faces: tuple[str, ...], switches: tuple[float, ...], *, contact_rows: bool = True,
              warm: bool = False,
              offsets: Mapping[int, Sequence[OffsetSeries]] | None = None,
              start: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
              problem: FitProblem | None = None) -> ScoredSequence:
        """The candidate's fit: first without the contact rows (cone, reach, obstacles and the ends).

        ``warm``: the first linearisation at the universal path instead of the free DMP's; ``start``:
        at this path instead (its times [s] (T,) and positions (T, 2) [m]); ``offsets``: see
        :meth:`problem`; ``problem``: that :meth:`problem` of ``faces``, ``switches`` and ``offsets``
        when the caller has it already (not yet solved: its contact rows share out their budget at
        their first linearisation), else it is built here.

        Without ``contact_rows`` (screening) the contacts that path needs and the excess contact
        travel beyond ``max_contacts`` contacts per push are only measured, for the cost. With them
        (the final fit), the fit is repeated with the contact rows (:class:`ContactOnFace`, first
        linearised at that path) when a push needs more than ``max_contacts`` contacts. Every fit
        carries the rolling penalty (:class:`tooltransfer.planner.planning.oe.objectives.RollingPenalty`), so the number
        of contacts is priced, not only bounded. A candidate the first stage finds infeasible is so for
        the second.
        """
        problem = self.problem(faces, switches, offsets) if problem is None else problem
        kw = {"tol": self.opts.tol, "max_scp": self.opts.max_scp, "scp_rtol": self.opts.scp_rtol}
        contact = [c for c in problem.constraints if isinstance(c, ContactOnFace)]
        first = replace(problem, constraints=[c for c in problem.constraints if not isinstance(c, ContactOnFace)])
        x_start = None
        if warm or start is not None:
            td = first.t_dense
            tt, xx = (self.t, self.universal) if start is None else start
            x_start = np.column_stack([np.interp(td, tt, xx[:, j]) for j in range(2)])
        res = solve_fit(first, x_start=x_start, **kw)
        scored = ScoredSequence(faces, switches, res, self.opts.accept)
        if not contact or res.rollout is None or not scored.feasible:
            return scored
        roll = res.rollout
        t = roll.t  # on the grid's own times, as the windows are

        def counts(r: FitResult) -> list[int]:
            assert r.rollout is not None
            return [max(1, int(np.ceil(c.need(t, r.rollout.x, r.rollout.v) / (c.hi - c.lo) - 1e-9))) for c in contact]

        need = counts(res)
        excess = sum(max(0.0, c.need(t, roll.x, roll.v) - c.max_contacts * (c.hi - c.lo)) for c in contact)
        n = sum(need) + len(faces) - len(contact)
        if not contact_rows:
            return replace(scored, contacts=n, excess=excess)
        if excess > 0.0:
            res = solve_fit(problem, x_start=roll.x, **kw)
            scored = ScoredSequence(faces, switches, res, self.opts.accept)
            if res.rollout is None or not scored.feasible:
                return scored
            need = counts(res)
            n = sum(need) + len(faces) - len(contact)
            scored = replace(scored, contacts=n)
        return scored

    def cost(self, s: ScoredSequence) -> float:
        """Half the mean squared deviation [m^2], plus the prices of the face changes and the
        re-contacts, plus the squared excess contact travel of a screening fit [m^2] (what the
        contact rows would have to bend away)."""
        if not s.feasible:
            return np.inf
        recontacts = max(0, s.contacts - len(s.faces))
        return (s.result.objective + self._offset + self.opts.switch_price * (len(s.faces) - 1)
                + self.opts.recontact_price * recontacts + s.excess**2)

    @property
    def _offset(self) -> float:
        """Constant the tracking objective drops (so costs read as half the mean squared deviation
        [m^2]): ``0.5 mean |x_free - ref|^2`` on the grid, the same for every candidate."""
        if self._const is None:
            free = self.problem((next(iter(self.frames)),), ()).affine("grid").x_free
            self._const = 0.5 * float(np.mean(np.sum((free - self.universal) ** 2, axis=1)))
        return self._const
