"""A guided path fitted one face at a time: each run of one face its own constrained DMP fit, from rest
to rest, the object standing still at every change of face; a run may use at most ``oe.max_contacts``
contacts of its face, as one push of the one fit may.

The guided search (:mod:`tooltransfer.planner.planning.oe.guided`) proposes a path of many short
straight pushes; fitted as one DMP over the whole duration
(:func:`~tooltransfer.planner.planning.oe.qp_variant.condense_sequence`) a long path with many turns
asks more of the basis functions than they give, and the fit fails on its cone and end rows where each
run alone fits easily. Here every run is fitted by
:func:`~tooltransfer.planner.planning.oe.qp_variant.condense_sequence` with the same rows (heading cone,
reach at both ends of the usable contact range, contact on the face, obstacles with the margin, the run's
end reached at rest) and realised by the inverse push model; a run whose fit fails is cut in two at its
middle step (the object stops there and the face touches it again: a re-contact), down to
:data:`MIN_RUN` of path. The pieces are joined on one time axis: each starts where and when the one
before it stopped, so the joined path is continuous, at rest at every joint.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.planning.oe.push_plan import Push, PushPlan
from tooltransfer.planner.planning.oe.qp_options import QPOptions
from tooltransfer.planner.planning.oe.qp_variant import condense_sequence
from tooltransfer.planner.planning.setting import Setting

__all__ = ["MIN_RUN", "fit_runs"]

#: Shortest stretch of the guided path [m] a failed run is cut down to before the fit gives up.
MIN_RUN = 0.006


Window = tuple[float, float] | None


def _runs(faces: tuple[str, ...], windows: Sequence[Window], runs: Sequence[int],
          ) -> list[tuple[str, Window, int, int]]:
    """``(face, contact window, first step, one past the last step)`` of each run of one face (one
    window, one run number) in the steps' ``faces``, ``windows`` and ``runs``."""
    out: list[tuple[str, Window, int, int, int]] = []
    for k, (f, w, r) in enumerate(zip(faces, windows, runs, strict=True)):
        if out and out[-1][:2] == (f, w) and out[-1][4] == r:
            out[-1] = (f, w, out[-1][2], k + 1, r)
        else:
            out.append((f, w, k, k + 1, r))
    return [run[:4] for run in out]


def _fit_run(xy: NDArray[np.float64], times: NDArray[np.float64], face: str, setting: Setting,
             options: QPOptions) -> list[PushPlan] | str:
    """The run ``xy`` (K, 2) [m] at ``times`` (K,) [s] pushed by ``face`` as one fit, or as the fits of
    its halves (recursively) where that fails; the reason of the first failure that cannot be cut."""
    plan = condense_sequence(times, xy, setting, xy[-1], (face,), (), options)
    if plan.status == "solved":
        return [plan]
    length = float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))
    if xy.shape[0] < 3 or length < 2 * MIN_RUN:
        return plan.reason
    m = xy.shape[0] // 2
    parts: list[PushPlan] = []
    for lo, hi in ((0, m + 1), (m, xy.shape[0])):
        got = _fit_run(xy[lo:hi], times[lo:hi], face, setting, options)
        if isinstance(got, str):
            return got
        parts += got
    return parts


def _join(pieces: list[PushPlan]) -> PushPlan:
    """One push plan of ``pieces`` fitted one after another (each starting where the one before ended):
    their samples on one time axis (the joint sample kept once), their pushes with their sample indices
    moved, a push that continues the face of the one before it a re-contact."""
    ts, xs, vs, refs = [], [], [], []
    pushes: list[Push] = []
    offset = 0
    for i, p in enumerate(pieces):
        drop = 1 if i else 0  # the first sample of a later piece is the last of the one before
        ts.append(p.t[drop:])
        xs.append(p.object_xy[drop:])
        vs.append(p.object_v[drop:])
        refs.append(p.universal[drop:])
        for k, push in enumerate(p.pushes):
            samples = push.samples + offset - drop
            again = k == 0 and bool(pushes) and pushes[-1].face == push.face
            pushes.append(replace(push, samples=samples, recontact=push.recontact or again))
        offset += p.t.size - drop
    return PushPlan("qp", "solved", np.concatenate(ts), np.concatenate(xs), np.concatenate(vs),
                    np.concatenate(refs), pushes=tuple(pushes), n_qp=sum(p.n_qp for p in pieces),
                    metrics={"compute_time": sum(p.metrics.get("compute_time", 0.0) for p in pieces),
                             "piecewise_fits": float(len(pieces))})


def fit_runs(xy: NDArray[np.float64], step_faces: tuple[str, ...], times: NDArray[np.float64],
             setting: Setting, options: QPOptions, windows: Sequence[Window] = (),
             runs: Sequence[int] = ()) -> PushPlan:
    """The guided path ``xy`` (K, 2) [m] at ``times`` (K,) [s] (``step_faces`` (K - 1,): the face of each
    step; ``windows``: the contact window [m] of each step, :func:`~.guided_moves.contact_windows`, or
    none; ``runs``: the run of its face each step is in, where the search started a new one) fitted
    run by run (module docstring); ``infeasible`` with the reason of the run that cannot be fitted."""
    pieces: list[PushPlan] = []
    k = len(step_faces)
    for face, window, a, b in _runs(step_faces, windows or (None,) * k, runs or (0,) * k):
        opts = options.model_copy(update={"contact_windows": {face: window}}) if window else options
        got = _fit_run(xy[a:b + 1], times[a:b + 1], face, setting, opts)
        contacts = 0 if isinstance(got, str) else sum(len(p.pushes) for p in got)
        if contacts > options.max_contacts:  # the one fit's bound on one push's contacts, for the whole run
            got = (f"its pieces need {contacts} contacts of the face (oe.max_contacts: {options.max_contacts} "
                   "contacts per push)")
        if isinstance(got, str):
            empty, at = np.zeros((0, 2)), np.round(xy[a], 4).tolist()
            return PushPlan("qp", "infeasible", np.zeros(0), empty, empty, xy,
                            reason=f"fitted run by run, the run of {face!r} from {at} m: {got}")
        pieces += got
    return _join(pieces)
