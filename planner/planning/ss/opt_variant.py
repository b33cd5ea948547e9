"""The ``opt`` variant: a smooth, non-penetrating switch path near the ``dmp`` one, solved with CasADi
and checked exactly with shapely (docs/design.md section 6; the NLP in :mod:`tooltransfer.planner.planning.ss.nlp`).

1. The ``dmp`` path (:func:`tooltransfer.planner.planning.ss.dmp_variant.recombine`) at the N knots' times is the
   reference. The primal initial guess (separating directions from its geometry) is the ``dmp`` path when it
   keeps out of the C-obstacle (``init="auto"``), else a path round the C-obstacle
   (:mod:`tooltransfer.planner.planning.ss.initial`; the ``dmp`` path of a new tool often goes right through the object,
   a start from which IPOPT can run out of iterations); when the NLP ends without a solution the
   next start is tried (the other way round; ``max_starts``), each try an attempt in ``info``.
   Optionally the dual values of the cached solver's last successful solve (``warm_duals``, off by
   default: slower, see ``OptOptions``), with IPOPT's ``warm_start_init_point``.
2. Contact poses that already overlap the object (another part of the tool than the face) or an
   obstacle make the switch infeasible before any solve, as do unreachable ones.
3. The margin to the object is ``margin`` over the middle of the path, ramped linearly to 0 at the
   two contact knots over ``ramp_share`` of the knots at each end; to the obstacles it ramps from
   ``min(margin, half the contact poses' clearance)`` to ``margin``.
   A family of reach rows is left out when the ``dmp`` path and the start keep ``reach_band`` from
   its boundary, an obstacle when they keep the tool ``body_band`` from it. Steps between knots are
   bounded (``step_factor``, ``min_step``): no tunnelling.
4. After the solve, the swept outline between knots is measured exactly with shapely
   (:mod:`tooltransfer.planner.planning.ss.verify`) and the reach on a path 4 times denser
   (:func:`tooltransfer.tools.omni.ik.joint_path`).
   A penetration deeper than ``touch_tol`` (the two contacts touch, so a few micrometres of swept
   hull at the contact steps is contact, not penetration) or a reach violation triggers a refinement:
   1.5 times the knots and 1.5 times the margin plus the depth found, up to ``max_refine`` times; if
   it still fails the result is ``failed`` with the numbers, never a silent path.
5. A solver that ends without a feasible point from every start gives ``infeasible`` with the
   constraint family of the largest violation and the starts tried (the NLP is local: the reason
   says so).
"""

from __future__ import annotations

import functools
import itertools
import math
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace

import numpy as np
import shapely
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.learning.switch_skill import SwitchSkill
from tooltransfer.planner.learning.virtual_motion import Way
from tooltransfer.planner.planning.ss.bodies import UNIT, Body, all_bodies
from tooltransfer.planner.planning.ss.dmp_variant import measure, recombine
from tooltransfer.planner.planning.ss.initial import c_obstacle, round_paths
from tooltransfer.planner.planning.ss.interrupts import keep_interrupts
from tooltransfer.planner.planning.ss.nlp import MODELS, SEPARATORS, SOLVERS, SwitchNLP, get_nlp
from tooltransfer.planner.planning.ss.result import SwitchPath
from tooltransfer.planner.planning.ss.separator_guess import initial_separators
from tooltransfer.planner.planning.ss.switch_task import SwitchTask
from tooltransfer.planner.planning.ss.verify import pose_depth_and_gap, tool_geometry
from tooltransfer.problems.task import SSOptions, schema_default
from tooltransfer.tools.contact import Contact
from tooltransfer.tools.objects import Disc
from tooltransfer.tools.omni.heading import heading
from tooltransfer.tools.omni.ik import joint_path
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.omni.reach import LinearRows, ReachSector, reach_sector, wedge_rows


def _contact_checks(task: SwitchTask, contacts: tuple[Contact, Contact], touch_tol: float
                    ) -> tuple[str | None, float]:
    """Why the contact poses make the switch impossible (or None), and their smallest clearance [m]
    from the obstacles (inf without obstacles)."""
    gap = np.inf
    for label, c in zip(("start", "end"), contacts, strict=True):
        d, _ = pose_depth_and_gap(task.tool, c.pose, task.shape)
        if d > touch_tol:
            return (f"the {label} contact pose ({c.face!r}) overlaps the object by {1e3 * d:.3f} mm "
                    "(another part of the tool reaches into it)"), gap
        for i, o in enumerate(task.obstacles):
            d, g = pose_depth_and_gap(task.tool, c.pose, o)
            if d > 0.0:
                return f"the {label} contact pose ({c.face!r}) overlaps obstacle {i} by {1e3 * d:.3f} mm", gap
            gap = min(gap, g)
    return None, gap


@functools.lru_cache(maxsize=16)
def _reach(platform: OmniPlatform) -> tuple[ReachSector, LinearRows]:
    return reach_sector(platform), wedge_rows(platform)


def reach_slacks(platform: OmniPlatform, xy: NDArray[np.float64]) -> NDArray[np.float64]:
    """Smallest distances [m] (3,) of the points ``xy`` (K, 2) from the inner circle, the outer circle
    and the waist half-planes of the reach sector (negative outside)."""
    sec, wr = _reach(platform)
    r = np.hypot(*(xy - sec.centre).T)
    return np.array([np.min(r - sec.r_in), np.min(sec.r_out - r), np.min(wr.h - xy @ wr.G.T)])


def reach_slack(platform: OmniPlatform, xy: NDArray[np.float64]) -> float:
    """Smallest distance [m] of the points ``xy`` (K, 2) from the boundary of the reach sector
    (annulus radii and waist half-planes; negative outside)."""
    return float(np.min(reach_slacks(platform, xy)))


def ramp(n_knots: int, share: float) -> NDArray[np.float64]:
    """Margin ramp (N,): 0 at the two end knots, 1 from ``share`` of the knots inwards, linear between."""
    k = np.arange(n_knots)
    width = max(1, math.ceil(share * (n_knots - 1)))
    return np.minimum(1.0, np.minimum(k, n_knots - 1 - k) / width)


def _violations(nlp: SwitchNLP, z: NDArray[np.float64], p: NDArray[np.float64]) -> list[tuple[str, float]]:
    """Constraint families violated at ``z`` with their largest violation [m], worst first."""
    g = np.asarray(nlp.rows(z, p)).ravel()
    worst: dict[str, float] = {}
    for name, a, b in nlp.families:
        if b > a:
            v = float(np.max(np.maximum(0.0, nlp.lbg[a:b] - g[a:b]))) * UNIT
            if v > 1e-10:
                worst[name] = max(v, worst.get(name, 0.0))
    return sorted(worst.items(), key=lambda kv: -kv[1])


def _length(x: NDArray[np.float64]) -> float:
    """Length [m] of the polyline ``x`` (N, 2)."""
    return float(np.sum(np.hypot(*np.diff(x, axis=0).T)))


def _objective(x: NDArray[np.float64], ref: NDArray[np.float64], smooth: float) -> float:
    """The NLP's objective [mm^2] at the path ``x`` (N, 2) [m] with the reference ``ref`` (N, 2) [m]."""
    xm, rm = x / UNIT, ref / UNIT
    acc = xm[2:] - 2 * xm[1:-1] + xm[:-2]
    return float(np.sum((xm - rm) ** 2) / len(xm) + smooth * np.sum(acc**2))


def _starts(task: SwitchTask, ref: SwitchPath, shapes: tuple, margin: float, smooth: float, init: str
            ) -> Iterator[tuple[str, NDArray[np.float64]]]:
    """Initial paths (label, (N, 2) [m]) to start the NLP from, in order, lazily
    (:mod:`tooltransfer.planner.planning.ss.initial`):
    the ``dmp`` path first when it stays out of the C-obstacle (at the middle heading, within
    ``margin``), else the paths round the C-obstacle, the one with the smaller objective first, and
    the others after."""
    dmp = ("dmp", ref.xy)
    if init == "dmp":
        yield dmp
        return
    psi = float(np.mean(ref.yaw))
    cobs = c_obstacle(task.tool, psi, shapes, margin)
    inner = ref.xy[1:-1]
    inside = shapely.contains_xy(cobs, inner[:, 0], inner[:, 1])
    clear = not inside.any() or float(shapely.distance(shapely.boundary(cobs), shapely.points(inner[inside])).max()) \
        <= margin
    if clear:
        yield dmp
    rounds = sorted(round_paths(task.tool, ref.xy[0], ref.xy[-1], psi, shapes, margin, len(ref.xy), cobs=cobs),
                    key=lambda x: _objective(x, ref.xy, smooth))
    yield from ((f"round {i + 1}", x) for i, x in enumerate(rounds))
    if not clear:
        yield dmp


def _near_obstacles(task: SwitchTask, paths: Sequence[NDArray[np.float64]], band: float) -> set[int]:
    """Indices of the obstacles within ``band`` [m] of the tool (a disc of its radius about the
    reference point) at some knot of ``paths`` (each (N, 2) [m])."""
    _, rho = tool_geometry(task.tool)
    pts = np.vstack(paths)
    out = set()
    for i, o in enumerate(task.obstacles):
        if isinstance(o, Disc):
            gap = float(np.min(np.hypot(*(pts - o.centre).T))) - o.radius
        else:
            gap = float(np.min(shapely.distance(shapely.points(pts), o)))
        if gap - rho <= band:
            out.add(i)
    return out


@dataclass(frozen=True)
class OptOptions:
    """Options of the ``opt`` variant (module docstring), checked when built.

    Attributes:
        n_knots: N, knots of the NLP (first try; the task schema's ``ss.n_knots`` default).
        margin: clearance [m] demanded over the middle of the path (first try).
        model: ``"pieces"`` (the tool's convex pieces with separating directions) or ``"capsule"``
            (the capsule enclosing the tool, disc bodies only).
        solver: a name in :data:`tooltransfer.planner.planning.ss.nlp.SOLVERS` (``"ipopt"``, ``"sqp"``).
        touch_tol: penetration depth [m] accepted as touching at the two contacts.
        ramp_share: share of the knots over which the margin ramps up at each end.
        max_refine: refinements after a failed exact check.
        smooth: weight of the squared second differences against the squared distance to the
            ``dmp`` path (both in mm^2).
        warm_duals: pass the cached solver's last dual values (primal: the start, ``init``). Off by
            default: the duals of the previous, different switch make solves slower
            (``benchmarks/bench_ss.py``; figures in benchmarks/README.md).
        way: which way round the object the virtual motion goes.
        reach_band: each family of reach rows (inner circle, outer circle, waist wedge) is left out of
            the NLP when the ``dmp`` path and the start keep this distance [m] from its boundary (a
            smaller NLP); the exact check still tests reach, and a violation puts all rows back for
            the refinement. None: always in.
        init: the NLP's initial path: ``"auto"`` (the ``dmp`` path when it keeps out of the
            C-obstacle, else a path round it, :mod:`tooltransfer.planner.planning.ss.initial`), ``"dmp"`` (always the
            ``dmp`` path).
        max_starts: initial paths tried (in the order of ``init``) when the NLP ends without a solution
            (each try is an attempt in ``info["attempts"]``, timed).
        step_factor, min_step: the largest step between knots [m] is ``max(step_factor * L / (N - 1),
            min_step)`` with ``L`` the length of the start path (:mod:`tooltransfer.planner.planning.ss.nlp`, no
            tunnelling).
        separators: the non-penetration rows of disc bodies, ``"distance"`` (exact signed distance, no
            extra variables), ``"vector"`` or ``"angle"`` (separating directions);
            :data:`tooltransfer.planner.planning.ss.nlp.SEPARATORS` and the module docstring there give the
            measurements.
        body_band: an obstacle is left out of the NLP when every knot of the ``dmp`` path and of the
            start keeps the tool (its radius about the reference point) this far [m] from it; the
            exact check still tests it, and a penetration puts every obstacle back for the
            refinement. None: always in.
    """

    n_knots: int = schema_default(SSOptions, "n_knots")
    margin: float = 1e-3
    model: str = "pieces"
    solver: str = "ipopt"
    touch_tol: float = 5e-6
    ramp_share: float = 0.15
    max_refine: int = 2
    smooth: float = 10.0
    warm_duals: bool = False
    way: Way | float = "short"
    reach_band: float | None = 0.03
    init: str = "auto"
    max_starts: int = 2
    step_factor: float = 2.5
    min_step: float = 3e-3
    separators: str = "distance"
    body_band: float | None = 0.01

    def __post_init__(self) -> None:
        if self.solver not in SOLVERS:
            raise InputError("solver", f"one of {', '.join(SOLVERS)}", repr(self.solver))
        if self.model not in MODELS:
            raise InputError("model", f"one of {', '.join(MODELS)}", repr(self.model))
        if self.separators not in SEPARATORS:
            raise InputError("separators", f"one of {', '.join(SEPARATORS)}", repr(self.separators))
        if not (np.isfinite(self.margin) and self.margin > 0):
            raise InputError("margin", "a positive length [m]", repr(self.margin))
        if not (np.isfinite(self.touch_tol) and self.touch_tol >= 0):
            raise InputError("touch_tol", "a length >= 0 [m]", repr(self.touch_tol))
        if self.init not in ("auto", "dmp"):
            raise InputError("init", "'auto' or 'dmp'", repr(self.init))
        if not isinstance(self.max_starts, int) or self.max_starts < 1:
            raise InputError("max_starts", "an integer >= 1", repr(self.max_starts))
        for name, value in (("step_factor", self.step_factor), ("min_step", self.min_step)):
            if not (np.isfinite(value) and value > 0):
                raise InputError(name, "a positive number", repr(value))
        for name, band in (("reach_band", self.reach_band), ("body_band", self.body_band)):
            if band is not None and not (np.isfinite(band) and band >= 0):
                raise InputError(name, "None or a length >= 0 [m]", repr(band))


@dataclass
class _Round:
    """The NLP of one refinement level, set up for ``n_knots`` knots and the margin ``margin`` [m]:
    the problem, its parameters and bounds, the bodies it keeps and the starts to try, in order."""

    n_knots: int
    margin: float
    nlp: SwitchNLP
    built: bool
    bodies: list[Body]
    use_reach: tuple[bool, bool, bool]
    p: NDArray[np.float64]
    lbx: NDArray[np.float64]
    ubx: NDArray[np.float64]
    starts: Iterator[tuple[str, NDArray[np.float64]]]


def _set_up(task: SwitchTask, ref: SwitchPath, every_body: list[Body], obs_gap: float, n_knots: int, margin: float,
            opts: OptOptions, all_reach: bool, all_obstacles: bool) -> _Round:
    """The NLP of one level (step 3 of the module docstring): reach rows when the reference or the
    first start come near the reach boundary (all of them when ``all_reach``), the obstacles the
    tool comes within ``body_band`` of (all when ``all_obstacles``), the ramped margins."""
    N, m = n_knots, margin
    shapes = (task.shape, *task.obstacles)
    starts = _starts(task, ref, shapes, m, opts.smooth, opts.init)
    first = next(starts)
    near = np.minimum(reach_slacks(task.omni, ref.xy), reach_slacks(task.omni, first[1])) < (
        np.inf if opts.reach_band is None else opts.reach_band)
    use_reach = (True, True, True) if all_reach else (bool(near[0]), bool(near[1]), bool(near[2]))
    # obstacles the tool cannot come within body_band of from the reference or the first start are
    # left out (the exact check still tests them; a penetration puts them all back)
    keep = _near_obstacles(task, (ref.xy, first[1]), np.inf if all_obstacles else opts.body_band)
    bodies = [b for b in every_body if b.family == "object" or int(b.family.split()[1]) in keep]
    nlp, built = get_nlp(task.tool, N, task.omni, bodies, model=opts.model, solver=opts.solver, smooth=opts.smooth,
                         reach=use_reach, separators=opts.separators)
    r = ramp(N, opts.ramp_share)
    m_obj = m * r
    m_obs = r * m + (1 - r) * min(m, 0.5 * obs_gap)
    p = np.concatenate([ref.xy.ravel() / UNIT, m_obj / UNIT, m_obs / UNIT, *[b.data for b in bodies], [0.0]])
    lbx = np.full(nlp.n_vars, -np.inf)
    ubx = np.full(nlp.n_vars, np.inf)
    for k in (0, N - 1):
        lbx[2 * k:2 * k + 2] = ubx[2 * k:2 * k + 2] = ref.xy[k] / UNIT
    return _Round(N, m, nlp, built, bodies, use_reach, p, lbx, ubx, itertools.chain([first], starts))


def _solve(rnd: _Round, task: SwitchTask, ref: SwitchPath, opts: OptOptions, info: dict[str, object]
           ) -> tuple[NDArray[np.float64] | None, SwitchPath | None]:
    """The NLP from each start in turn (at most ``max_starts``, step 1), each try appended to
    ``info["attempts"]``: the solution (or None) and the failure of the last start that failed."""
    nlp, p, N = rnd.nlp, rnd.p, rnd.n_knots
    attempts: list[dict[str, object]] = info["attempts"]  # type: ignore[assignment]
    built = rnd.built
    failure: SwitchPath | None = None
    for label, x_init in itertools.islice(rnd.starts, opts.max_starts):
        # steps up to step_factor times the start's mean step (and at least min_step)
        p[-1] = max(opts.step_factor * _length(x_init) / (N - 1), opts.min_step) / UNIT
        xy_mm = x_init / UNIT
        seps = initial_separators(nlp, xy_mm, heading(task.omni, x_init), rnd.bodies)
        z0 = np.concatenate([xy_mm.ravel(), seps.ravel(order="F")])
        args = {"x0": z0, "p": p, "lbx": rnd.lbx, "ubx": rnd.ubx, "lbg": nlp.lbg, "ubg": nlp.ubg}
        if opts.warm_duals and nlp.last_duals is not None:
            args["lam_x0"], args["lam_g0"] = nlp.last_duals
        t0 = time.perf_counter()
        with keep_interrupts():  # CasADi turns a Ctrl-C into a failed solve
            sol = nlp.solver(**args)
        t_solve = time.perf_counter() - t0
        st = nlp.solver.stats()
        z = np.asarray(sol["x"]).ravel()
        rec: dict[str, object] = {
            "n_knots": N, "margin": rnd.margin, "start": label, "built": built, "reach_rows": rnd.use_reach,
            "build_time": nlp.build_time if built else 0.0, "solve_time": t_solve,
            "status": st.get("return_status", ""), "iterations": int(st.get("iter_count", -1))}
        attempts.append(rec)
        built = False
        if st.get("success", False):
            info["x_start"] = x_init
            nlp.last_duals = (np.asarray(sol["lam_x"]).ravel(), np.asarray(sol["lam_g"]).ravel())
            return z, None
        viol = _violations(nlp, z, p)
        status = "infeasible" if viol and viol[0][1] > 1e-7 else "failed"
        listed = ", ".join(f"{name} by {1e3 * v:.3f} mm" for name, v in viol)
        tried = ", ".join(str(a["start"]) for a in attempts if a["n_knots"] == N)
        why = (f"the NLP ({opts.solver}, local) ended with {rec['status']!r}: no feasible switch path found "
               f"(started from: {tried}); violated at its last iterate: {listed}" if status == "infeasible"
               else f"the NLP ({opts.solver}) ended with {rec['status']!r} at a feasible point (started from: {tried})")
        failure = SwitchPath("opt", status, why, start=ref.start, end=ref.end)
    return None, failure


def _check(task: SwitchTask, ref: SwitchPath, z: NDArray[np.float64], n_knots: int, rec: dict[str, object]
           ) -> tuple[SwitchPath, float]:
    """The solved path measured exactly (step 4): the swept outline with shapely and the reach on a
    path 4 times denser; the path and its largest reach violation [rad], both also noted in ``rec``."""
    assert ref.start is not None and ref.end is not None
    N = n_knots
    xy = z[:2 * N].reshape(N, 2) * UNIT
    xy[0], xy[-1] = ref.start.pose.position, ref.end.pose.position
    yaw = heading(task.omni, xy)
    t0 = time.perf_counter()
    path = measure(SwitchPath("opt", "solved", "", ref.t, xy, yaw, ref.start, ref.end), task)
    dense = np.vstack([xy[:-1] + f * (xy[1:] - xy[:-1]) for f in (0.0, 0.25, 0.5, 0.75)] + [xy[-1:]])
    reach = float(np.max(joint_path(task.omni, dense).violation))
    rec["verify_time"] = time.perf_counter() - t0
    rec["penetration"] = path.max_penetration
    rec["reach_violation"] = reach
    return path, reach


def optimize(skill: SwitchSkill, task: SwitchTask, options: OptOptions | None = None) -> SwitchPath:
    """The ``opt`` switch path of ``task`` (module docstring) from the SS ``skill`` (it gives the
    ``dmp`` reference path), with ``options`` (default :class:`OptOptions`)."""
    t_start = time.perf_counter()
    opts = options if options is not None else OptOptions()
    if not isinstance(opts, OptOptions):
        raise InputError("options", "an OptOptions", type(opts).__name__)
    ref = recombine(skill, task, n_samples=opts.n_knots, way=opts.way, measured=False)
    if not ref.ok:
        return replace(ref, variant="opt")
    assert ref.start is not None and ref.end is not None
    why, obs_gap = _contact_checks(task, (ref.start, ref.end), opts.touch_tol)
    if why is not None:
        return SwitchPath("opt", "infeasible", why, start=ref.start, end=ref.end)
    every_body = all_bodies(task.shape, task.obstacles)
    info: dict[str, object] = {"attempts": [], "k1": ref.info["k1"], "model": opts.model, "solver": opts.solver,
                               "init": opts.init}
    attempts: list[dict[str, object]] = info["attempts"]  # type: ignore[assignment]
    N, m = opts.n_knots, opts.margin
    any_violation = False
    all_obstacles = opts.body_band is None
    level = 0
    while level <= opts.max_refine:
        if len(ref.xy) != N:
            ref = recombine(skill, task, n_samples=N, way=opts.way, measured=False)
        rnd = _set_up(task, ref, every_body, obs_gap, N, m, opts, any_violation, all_obstacles)
        solved, failure = _solve(rnd, task, ref, opts, info)
        if solved is None:
            assert failure is not None
            info.update(iterations=sum(int(a["iterations"]) for a in attempts), time=time.perf_counter() - t_start)
            return replace(failure, info=info)
        path, reach = _check(task, ref, solved, N, attempts[-1])
        any_violation = any_violation or reach > 0.0
        if path.max_penetration <= opts.touch_tol and reach == 0.0:
            info.update(iterations=sum(int(a["iterations"]) for a in attempts),
                        refinements=level, n_knots=N, margin=m, time=time.perf_counter() - t_start)
            return replace(path, info=info)
        if len(rnd.bodies) < len(every_body) and path.obstacle_penetration > opts.touch_tol:
            all_obstacles = True  # an obstacle left out was hit: the same knots and margin with all of them
            continue
        level += 1
        N, m = math.ceil(1.5 * N), 1.5 * m + path.max_penetration
    last = attempts[-1]
    return SwitchPath(
        "opt", "failed",
        f"the exact check failed after {opts.max_refine} refinements: penetration {1e3 * last['penetration']:.4f} mm, "
        f"reach violation {last['reach_violation']:.3g} rad",
        start=ref.start, end=ref.end, info={**info, "time": time.perf_counter() - t_start},
    )
