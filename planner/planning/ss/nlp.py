"""The switch NLP (the ``opt`` variant's solver problem), built once per structure and reused.

Decision variables (millimetres, :data:`tooltransfer.planner.planning.ss.bodies.UNIT`): the tool centre points ``X_k``
(N, 2) at N knots, plus separating variables where a row needs them (:data:`SEPARATORS`):

* ``"distance"`` (the default): none for a disc body; the row is the exact signed distance from the
  disc's centre to each convex piece, computed in the tool frame (module rows below): fewer
  variables and IPOPT iterations than ``"vector"`` with the same switches solved
  (``benchmarks/bench_ss.py``; figures in ``benchmarks/README.md``). Polygonal bodies keep the
  vector separators.
* ``"vector"``: per interior knot, convex piece of the tool and body, a separating direction ``n``
  (2,) with ``|n|^2 <= 1`` (plus an offset ``beta`` for a polygonal body);
* ``"angle"``: ``n = (cos phi, sin phi)``: one variable and no norm row, a smaller KKT system than
  ``"vector"`` but a worse tail of iteration counts (the angle must turn round where the vector can
  shrink through zero).

Heading: **a function of position through the Omni's waist** (:func:`tooltransfer.tools.omni.heading.heading_casadi`,
smooth inside the reach annulus), not fixed over the move: the tool's yaw at knot k is
``yaw(X_k)``, exactly the heading the arm will have there, so the vertices ``w = X_k + R(yaw(X_k)) v``
the constraints see are the ones the arm will place.

Rows (all smooth and analytic; no shapely inside the solver):

* non-penetration, piece-vs-disc, ``"distance"``: with ``l`` the disc's centre in the tool frame
  (``R(yaw)^T (c - X_k)``, so the piece's edges are constants), ``sd(l) >= R + m_k`` where ``sd`` is
  the least clamped point-to-edge distance when ``l`` is outside the piece (some edge line has it on
  its outer side) and the largest signed edge-line distance (negative) inside: exact, continuously
  differentiable outside, no extra variables (the clamped-distance idea of the capsule model applied
  to every edge);
* non-penetration, piece-vs-disc, ``"vector"``/``"angle"``: ``n . (w_i - c) >= R + m_k`` for every
  vertex ``w_i`` of the piece with ``|n| = 1`` (or ``|n|^2 <= 1``): the piece lies beyond the line
  at distance ``R + m_k`` from the centre, so its distance to the disc is at least ``m_k`` (exact for
  a convex piece: such ``n`` exists iff it is);
* piece-vs-convex polygon: ``n . w_i - beta >= m_k``, ``n . o_l <= beta``, ``|n| = 1`` (a separating
  line with a gap of at least ``m_k``);
* with the ``capsule`` model (a tool that is a segment grown by a radius ``r``) the clamped
  point-to-segment distance ``|c - a - t (b - a)| >= R + r + m_k``, ``t = clip(., 0, 1)``, and no
  extra variables (disc bodies only);
* the margin ``m_k`` is a parameter per knot, ramped down to 0 at the two contact knots (a constant
  margin is infeasible there: the tool touches the object); the end knots carry no rows (they are
  fixed at the contact poses by their bounds);
* step length: ``|X_{k+1} - X_k| <= s_max`` (a parameter), so the path cannot jump across a body
  between two knots (without it, paths tracking a ``dmp`` reference through the object put one knot
  on each side: 36 mm steps, 8 mm penetration between the knots);
* Omni reach at the interior knots: ``r_in^2 <= |X - b|^2 <= r_out^2`` (the annulus) and the two
  half-planes of the waist range (exact, :func:`tooltransfer.tools.omni.reach.wedge_rows`), each tightened by
  ``reach_margin``; each of the three families only when asked (the caller includes those whose
  boundary the path comes near).

Objective: ``sum_k |X_k - Xd_k|^2 / N + smooth * sum_k |X_{k+1} - 2 X_k + X_{k-1}|^2``, with ``Xd``
the ``dmp`` path (a parameter).

Solvers (:data:`SOLVERS`): ``"ipopt"`` (interior point; warm start with primal and dual values and
``warm_start_init_point``) and ``"sqp"`` (CasADi's ``sqpmethod`` with the ``qrqp`` active-set QP,
fast on the small capsule model; ``qpOASES`` is not used: it keeps state between calls).
Building an NLP: the rows of one interior knot are SX expressions, derived once and mapped over the
knots (:mod:`tooltransfer.planner.planning.ss.knot_rows`), and IPOPT gets these derivatives instead of ones
CasADi would derive from the whole problem (an SX Hessian of some 60,000 operations, slow to
build). A build's time is mostly Python making the expressions; :func:`get_nlp` caches one
per structure (tool, model, N, platform, body kinds, solver), and solves change only parameters,
bounds and the initial guess. The build and solve times are in ``benchmarks/README.md``
(``benchmarks/bench_ss.py``).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.planning.ss.bodies import UNIT, Body
from tooltransfer.planner.planning.ss.knot_rows import KnotRows, placed, triplet
from tooltransfer.tools.model import Tool
from tooltransfer.tools.omni.heading import heading_casadi
from tooltransfer.tools.omni.platform import OmniPlatform
from tooltransfer.tools.omni.reach import reach_sector, wedge_rows


@dataclass(frozen=True)
class Capsule:
    """A capsule tool model in the tool frame: segment ``a``-``b`` (2,) [m] grown by ``radius`` [m]."""

    a: NDArray[np.float64]
    b: NDArray[np.float64]
    radius: float

    @staticmethod
    def enclosing(tool: Tool, n_grid: int = 13) -> Capsule:
        """The capsule of least area covering every outline vertex among those whose segment lies on the
        tool frame's vertical line through the middle of the outline's width, with each end inset from
        the outline's extent by a fraction of its half width (a grid of ``n_grid`` insets per end)."""
        v = np.asarray(tool.outline.exterior.coords, dtype=np.float64)[:-1]
        x0 = 0.5 * (v[:, 0].min() + v[:, 0].max())
        half = 0.5 * (v[:, 0].max() - v[:, 0].min())
        best: Capsule | None = None
        best_area = np.inf
        for lo in np.linspace(0.0, half, n_grid):
            for hi in np.linspace(0.0, half, n_grid):
                a, b = np.array([x0, v[:, 1].min() + lo]), np.array([x0, v[:, 1].max() - hi])
                ab = b - a
                t = np.clip(((v - a) @ ab) / max(float(ab @ ab), 1e-18), 0.0, 1.0)
                r = float(np.max(np.hypot(*(v - a - t[:, None] * ab).T)))
                area = 2.0 * r * float(np.hypot(*ab)) + np.pi * r * r
                if area < best_area:
                    best, best_area = Capsule(a, b, r), area
        assert best is not None
        return best


def _ipopt(nlp: dict[str, Any], derivatives: Callable[[], dict[str, Any]], max_iter: int) -> Any:
    import casadi as ca

    # tol 1e-4 on the (mm, mm^2) scaled NLP error; the constraint violation keeps IPOPT's default
    # constr_viol_tol (1e-4 mm), and the exact shapely check decides penetration anyway. The
    # adaptive barrier update takes fewer iterations than the monotone one (the other IPOPT settings
    # tried are listed in benchmarks/README.md). calc_lam_p off: the parameters' multipliers are not
    # used (one evaluation less per solve). The derivatives are the NLP's own, mapped knot by knot
    # (build_nlp), not CasADi's of the whole MX graph.
    return ca.nlpsol("ss_ipopt", "ipopt", nlp, {
        **derivatives(), "print_time": False, "error_on_fail": False, "calc_lam_p": False,
        "ipopt": {"print_level": 0, "sb": "yes", "max_iter": max_iter, "tol": 1e-4, "acceptable_tol": 1e-3,
                  "mu_strategy": "adaptive", "warm_start_init_point": "yes", "warm_start_bound_push": 1e-3,
                  "warm_start_mult_bound_push": 1e-3, "warm_start_slack_bound_push": 1e-3, "mu_init": 1e-2,
                  "linear_solver": "mumps"},
    })


def _sqp(nlp: dict[str, Any], derivatives: Callable[[], dict[str, Any]], max_iter: int) -> Any:
    import casadi as ca

    # sqpmethod asks for other derivative functions (the whole Hessian, the Jacobian of f and g at
    # once), so ``derivatives`` is not called: the MX problem is expanded to SX and CasADi derives it
    # (slower to build, as fast to solve)
    return ca.nlpsol("ss_sqp", "sqpmethod", nlp, {
        "expand": True, "print_time": False, "print_header": False, "print_iteration": False, "print_status": False,
        "error_on_fail": False, "max_iter": max_iter, "qpsol": "qrqp",
        "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False, "error_on_fail": False},
    })


#: Registered NLP backends: name -> builder(nlp dict, a function giving the NLP's derivative functions
#: by nlpsol option (called only by a backend that uses them), max_iter) -> casadi Function.
SOLVERS: dict[str, Callable[[dict[str, Any], Callable[[], dict[str, Any]], int], Any]] = {"ipopt": _ipopt,
                                                                                          "sqp": _sqp}
MODELS: tuple[str, ...] = ("pieces", "capsule")
#: Non-penetration rows for disc bodies: the exact signed distance (no variables; the default), or
#: separating directions as a vector ``n`` with ``|n|^2 <= 1`` (two variables and a row) or as an angle
#: ``n = (cos phi, sin phi)`` (one variable, no norm row); module docstring.
SEPARATORS: tuple[str, ...] = ("vector", "angle", "distance")


@dataclass
class SwitchNLP:
    """A built switch NLP and what is needed to call it (module docstring).

    Attributes:
        key: the cache key; solver: the CasADi function; n_knots: N; model, solver_name.
        n_sep: separating variables per interior knot; sep_layout: ``(piece, body, offset, has_beta)``.
        families: ``(name, start, stop)`` row ranges of the constraint families.
        lbg, ubg: row bounds; reach_rows: ``(G, h)`` [mm] of the wedge (for the initial guess check).
        pieces: tool-frame vertices [mm] of each piece; capsule: the capsule model [mm] or None.
        build_time: [s]; rows: CasADi function (z, p) -> constraint rows (for the reasons);
        last_duals: ``(lam_x, lam_g)`` of the last successful solve (warm start).
    """

    key: tuple
    solver: Any
    n_knots: int
    model: str
    solver_name: str
    n_sep: int
    sep_layout: list[tuple[int, int, int, bool]]
    families: list[tuple[str, int, int]]
    lbg: NDArray[np.float64]
    ubg: NDArray[np.float64]
    pieces: list[NDArray[np.float64]]
    capsule: Capsule | None
    build_time: float
    n_params: int
    rows: Any = None
    angle: bool = False
    last_duals: tuple[NDArray[np.float64], NDArray[np.float64]] | None = field(default=None)

    @property
    def n_vars(self) -> int:
        return 2 * self.n_knots + (self.n_knots - 2) * self.n_sep


def _tool_key(tool: Tool) -> tuple[str, bytes]:
    return (tool.name, tool.outline.wkb)


def reach_families(reach: bool | tuple[bool, bool, bool]) -> tuple[bool, bool, bool]:
    """``(inner circle, outer circle, waist wedge)`` reach rows to build: all for True, none for False."""
    if isinstance(reach, bool):
        return (reach, reach, reach)
    inner, outer, wedge = (bool(v) for v in reach)
    return inner, outer, wedge


def _check_build(n_knots: int, bodies: Sequence[Body], model: str, solver: str, separators: str) -> None:
    """Reject an unknown solver, model or separator form, too few knots, or a capsule against a
    polygon (the capsule rows measure discs only), before any CasADi work."""
    if solver not in SOLVERS:
        raise InputError("solver", f"one of {', '.join(SOLVERS)}", repr(solver))
    if model not in MODELS:
        raise InputError("model", f"one of {', '.join(MODELS)}", repr(model))
    if not isinstance(n_knots, int) or n_knots < 5:
        raise InputError("n_knots", "an integer >= 5", repr(n_knots))
    if model == "capsule" and any(b.kind != "disc" for b in bodies):
        raise InputError("model", "'pieces' when the object or an obstacle is a polygon", "'capsule'")
    if separators not in SEPARATORS:
        raise InputError("separators", f"one of {', '.join(SEPARATORS)}", repr(separators))


@dataclass(frozen=True)
class _ToolRows:
    """How the tool enters the non-penetration rows: its model, convex ``pieces`` [mm] (tool
    frame) or ``capsule`` [mm], and the separators: their form (``angle``, or ``distance`` for the
    signed-distance rows of discs), the per-knot ``(piece, body, offset, has_beta)`` layout and
    the count ``n_sep`` of separating variables per interior knot."""

    model: str
    pieces: list[NDArray[np.float64]]
    capsule: Capsule | None
    angle: bool
    distance: bool
    sep_layout: list[tuple[int, int, int, bool]]
    n_sep: int

    @classmethod
    def of(cls, tool: Tool, bodies: Sequence[Body], model: str, separators: str) -> _ToolRows:
        """The tool's pieces (or capsule) in millimetres and the separating variables each pair of
        piece and body needs (none for a disc under ``"distance"``)."""
        angle = separators == "angle"
        pieces = [np.asarray(p.exterior.coords, dtype=np.float64)[:-1] / UNIT for p in tool.convex_pieces]
        capsule = None
        if model == "capsule":
            c = Capsule.enclosing(tool)
            capsule = Capsule(c.a / UNIT, c.b / UNIT, c.radius / UNIT)
        sep_layout: list[tuple[int, int, int, bool]] = []
        n_sep = 0
        distance = separators == "distance"
        if model == "pieces":
            for j in range(len(pieces)):
                for bi, b in enumerate(bodies):
                    poly = b.kind == "poly"
                    if distance and not poly:
                        continue  # the signed distance row needs no separating variables
                    sep_layout.append((j, bi, n_sep, poly))
                    n_sep += (1 if angle else 2) + (1 if poly else 0)
        return cls(model, pieces, capsule, angle, distance, sep_layout, n_sep)


class _Interior:
    """The tool at one interior knot (SX): its centre ``Xi, Yi`` [mm] and the heading's cosine and
    sine (the heading a function of position through the Omni's waist)."""

    def __init__(self, centre: Any, platform: OmniPlatform) -> None:
        import casadi as ca

        self.Xi, self.Yi = centre[0], centre[1]
        yaw = heading_casadi(platform, self.Xi * UNIT, self.Yi * UNIT)
        self.cos_k, self.sin_k = ca.cos(yaw), ca.sin(yaw)

    def world(self, v: NDArray[np.float64]) -> tuple[Any, Any]:
        """The tool-frame point ``v`` (2,) [mm] in the world at the knot."""
        return self.Xi + self.cos_k * v[0] - self.sin_k * v[1], self.Yi + self.sin_k * v[0] + self.cos_k * v[1]

    def tool_frame(self, cx: Any, cy: Any) -> tuple[Any, Any]:
        """The world point ``(cx, cy)`` in the tool frame at the knot (there the tool's outline is
        constant, so distance expressions and their Hessians stay small)."""
        rx, ry = cx - self.Xi, cy - self.Yi
        return self.cos_k * rx + self.sin_k * ry, self.cos_k * ry - self.sin_k * rx


def _body_rows(knots: _Interior, tr: _ToolRows, b: Body, bi: int, p: Any, m: Any, S: Any) -> list[Any]:
    """Non-penetration rows (SX scalars of one knot, each >= 0) of body ``b`` (number ``bi``, parameters ``p``,
    margin row ``m`` [mm]) against the tool: the capsule's distance, the signed distance of each
    piece to a disc, or the separating-line rows of each piece (separating variables ``S``)."""
    import casadi as ca

    per_knot: list[Any] = []
    if tr.model == "capsule":
        assert tr.capsule is not None
        lx, ly = knots.tool_frame(p[0], p[1])
        d2 = _clamped_d2(lx, ly, tr.capsule.a, tr.capsule.b - tr.capsule.a)
        per_knot.append(ca.sqrt(d2) - (p[2] + tr.capsule.radius + m))
    elif tr.distance and b.kind == "disc":
        lx, ly = knots.tool_frame(p[0], p[1])
        for verts in tr.pieces:
            per_knot.append(_signed_distance(verts, lx, ly) - (p[2] + m))
    else:
        for j, verts in enumerate(tr.pieces):
            off = next(o for (jj, bb, o, _) in tr.sep_layout if jj == j and bb == bi)
            if tr.angle:
                n0, n1 = ca.cos(S[off, :]), ca.sin(S[off, :])
                beta = S[off + 1, :] if b.kind == "poly" else None
            else:
                n0, n1 = S[off, :], S[off + 1, :]
                beta = S[off + 2, :] if b.kind == "poly" else None
            for v in verts:
                wx, wy = knots.world(v)
                if b.kind == "disc":
                    per_knot.append(n0 * (wx - p[0]) + n1 * (wy - p[1]) - (p[2] + m))
                else:
                    per_knot.append(n0 * wx + n1 * wy - beta - m)
            if b.kind == "poly":
                for vi in range(b.data.size // 2):
                    per_knot.append(beta - (n0 * p[2 * vi] + n1 * p[2 * vi + 1]))
            if not tr.angle:
                per_knot.append(1 - n0 * n0 - n1 * n1)
    return per_knot


def _reach_rows(knots: _Interior, platform: OmniPlatform, reach: bool | tuple[bool, bool, bool],
                reach_margin: float) -> list[Any]:
    """Reach rows (SX scalars of one knot, each >= 0, scaled to millimetres): inside the
    outer radius, outside the inner one and inside the wedge's two half-planes, each
    ``reach_margin`` [m] inside, as far as :func:`reach_families` keeps them."""
    sec = reach_sector(platform)
    wr = wedge_rows(platform)
    bx0, by0 = sec.centre / UNIT
    r_in, r_out = (sec.r_in + reach_margin) / UNIT, (sec.r_out - reach_margin) / UNIT
    Xi, Yi = knots.Xi, knots.Yi
    inner, outer, wedge = reach_families(reach)
    r2 = (Xi - bx0) ** 2 + (Yi - by0) ** 2
    per_knot = []
    if inner:
        per_knot.append((r2 - r_in**2) / r_in)
    if outer:
        per_knot.append((r_out**2 - r2) / r_out)
    for gi in range(2 if wedge else 0):
        per_knot.append(wr.h[gi] / UNIT - reach_margin / UNIT - (wr.G[gi, 0] * Xi + wr.G[gi, 1] * Yi))
    return per_knot


def build_nlp(
    tool: Tool, n_knots: int, platform: OmniPlatform, bodies: Sequence[Body], *, model: str = "pieces",
    solver: str = "ipopt", smooth: float = 10.0, reach_margin: float = 1e-4, max_iter: int = 150,
    reach: bool | tuple[bool, bool, bool] = True, separators: str = "distance",
) -> SwitchNLP:
    """Build the NLP (module docstring) for ``tool`` at ``n_knots`` knots against bodies of the kinds
    of ``bodies`` (their values are parameters of each solve). ``reach``: which reach row families
    (:func:`reach_families`) the interior knots get.

    Variables ``z = [vec(X) (2 N), vec(S) (n_sep, N - 2)]``; parameters
    ``p = [vec(Xd) (2 N), m_obj (N), m_obs (N), each body's data, s_max]``. The rows of each body and
    the reach rows read one interior knot each: they are derived for one knot and mapped
    (:class:`tooltransfer.planner.planning.ss.knot_rows.KnotRows`); the objective and the step rows, which
    couple neighbouring knots and are quadratic, are one SX function of the knots."""
    import casadi as ca

    t0 = time.perf_counter()
    _check_build(n_knots, bodies, model, solver, separators)
    N, K = n_knots, n_knots - 2
    tr = _ToolRows.of(tool, bodies, model, separators)
    n_vars = 2 * N + K * tr.n_sep
    sizes = [int(b.data.size) for b in bodies]
    n_params = 4 * N + sum(sizes) + 1
    z, p = ca.MX.sym("z", n_vars), ca.MX.sym("p", n_params)
    # one knot's variables: its centre, then its separators (z's order: knot k is column k + 1 of X)
    var_index = np.column_stack([2 * np.arange(1, N - 1), 2 * np.arange(1, N - 1) + 1,
                                 2 * N + tr.n_sep * np.arange(K)[:, None] + np.arange(tr.n_sep)]).astype(np.intp)
    v = ca.SX.sym("v", 2 + tr.n_sep)
    m = ca.SX.sym("m")
    knot = _Interior(v[:2], platform)
    S = v[2:] if tr.n_sep else None
    interior = KnotRows(var_index, n_vars)
    families: list[tuple[str, int, int]] = []
    count, off = 0, 4 * N
    for bi, (b, size) in enumerate(zip(bodies, sizes, strict=True)):
        q = ca.SX.sym(f"body{bi}", size)
        base = 2 * N if b.family == "object" else 3 * N  # m_obj or m_obs, at the interior knots
        margins = p[base + 1:base + N - 1].T
        n = interior.add(f"body{bi}", v, q, m, _body_rows(knot, tr, b, bi, q, m, S), p[off:off + size], margins)
        families.append((b.family, count, count + n))
        count, off = count + n, off + size
    start = count
    per_knot = _reach_rows(knot, platform, reach, reach_margin)
    if per_knot:
        count += interior.add("reach", v, ca.SX(0, 1), m, per_knot, ca.MX(0, 1), ca.MX(1, K))
    families.append(("reach", start, count))
    families.append(("step", count, count + N - 1))
    n_rows = count + N - 1
    whole = _objective_and_steps(N, smooth)
    xs, xd, s_max = z[:2 * N], p[:2 * N], p[-1]
    g = ca.vertcat(*interior.rows(z), whole.steps(xs, s_max))

    def derivatives() -> dict[str, Any]:
        """IPOPT's derivative functions: the gradient (stored dense: IPOPT reads it as a dense vector,
        so the separators' zeros must be stored ones), the Jacobian and the Lagrangian's Hessian."""
        lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", n_rows)
        f, grad = whole.with_grad(xs, xd)
        values, jacobians = interior.rows_and_jacobian(z, n_rows)
        steps, jac_steps = whole.steps_with_jac(xs, s_max)
        r, c = triplet(whole.steps_with_jac.sparsity_out(1))
        jac = sum(jacobians, placed(jac_steps, count + r, c, (n_rows, n_vars)))
        r, c = triplet(whole.hess.sparsity_out(0))
        hess = sum(interior.hessian(z, lam_g), placed(whole.hess(xs, s_max, lam_f, lam_g[count:]), r, c,
                                                      (n_vars, n_vars)))
        return {
            "grad_f": ca.Function("nlp_grad_f", [z, p], [f, ca.densify(ca.vertcat(grad, ca.MX(n_vars - 2 * N, 1)))],
                                  ["x", "p"], ["f", "grad_f_x"]),
            "jac_g": ca.Function("nlp_jac_g", [z, p], [ca.vertcat(*values, steps), jac], ["x", "p"],
                                 ["g", "jac_g_x"]),
            "hess_lag": ca.Function("nlp_hess_l", [z, p, lam_f, lam_g], [hess], ["x", "p", "lam_f", "lam_g"],
                                    ["triu_hess_gamma_x_x"]),
        }

    fn = SOLVERS[solver]({"x": z, "p": p, "f": whole.f(xs, xd), "g": g}, derivatives, max_iter)
    return SwitchNLP(
        key=(), solver=fn, n_knots=N, model=model, solver_name=solver, n_sep=tr.n_sep, sep_layout=tr.sep_layout,
        families=families, lbg=np.zeros(n_rows), ubg=np.full(n_rows, np.inf), pieces=tr.pieces,
        capsule=tr.capsule, build_time=time.perf_counter() - t0, n_params=n_params,
        rows=ca.Function("ss_rows", [z, p], [g]), angle=tr.angle,
    )


class _Whole(NamedTuple):
    """The objective and the step rows as SX functions of the knots ``x = vec(X)`` (2 N,) [mm], the
    reference ``xd`` (2 N,) [mm] and ``s_max`` [mm], one function per combination the NLP's callbacks
    need (an SX function computes all its outputs whenever it is called): ``f(x, xd)``,
    ``with_grad(x, xd) -> (f, grad f)``, ``steps(x, s_max)``, ``steps_with_jac(x, s_max) -> (steps,
    their Jacobian)`` and ``hess(x, s_max, lam_f, lam_s)``, the upper triangle of the Hessian of
    ``lam_f f + lam_s . steps`` (constant in ``x`` for f, whose Hessian does not depend on ``xd``)."""

    f: Any
    with_grad: Any
    steps: Any
    steps_with_jac: Any
    hess: Any


def _objective_and_steps(N: int, smooth: float) -> _Whole:
    """:class:`_Whole` for ``N`` knots: the objective ``|X - Xd|^2 / N + smooth * sum |X_{k+1} - 2 X_k +
    X_{k-1}|^2`` and the step rows ``(s_max^2 - |X_{k+1} - X_k|^2) / s_max >= 0`` (no tunnelling
    through a body between knots)."""
    import casadi as ca

    x, xd, s_max = ca.SX.sym("x", 2 * N), ca.SX.sym("xd", 2 * N), ca.SX.sym("s_max")
    X = ca.reshape(x, 2, N)
    dX = X[:, 1:] - X[:, :-1]
    step = ((s_max * s_max - (dX[0, :] ** 2 + dX[1, :] ** 2)) / s_max).T
    f = ca.sumsqr(x - xd) / N + smooth * ca.sumsqr(X[:, 2:] - 2 * X[:, 1:-1] + X[:, :-2])
    lam_f, lam_s = ca.SX.sym("lam_f"), ca.SX.sym("lam_s", N - 1)
    return _Whole(
        f=ca.Function("ss_objective", [x, xd], [f]),
        with_grad=ca.Function("ss_objective_grad", [x, xd], [f, ca.gradient(f, x)]),
        steps=ca.Function("ss_steps", [x, s_max], [step]),
        steps_with_jac=ca.Function("ss_steps_jac", [x, s_max], [step, ca.jacobian(step, x)]),
        hess=ca.Function("ss_whole_hess", [x, s_max, lam_f, lam_s],
                         [ca.triu(ca.hessian(lam_f * f + ca.dot(lam_s, step), x)[0])]))


def _signed_distance(verts: NDArray[np.float64], lx: Any, ly: Any) -> Any:
    """Signed distance [mm] from the point ``(lx, ly)`` (in the tool frame, [mm]) to the convex piece
    with vertices ``verts`` (V, 2) [mm]: outside, the least clamped point-to-edge distance (exact,
    continuously differentiable); inside, the largest signed distance to the edges' lines
    (negative). In the tool frame the edges are constants, so the expression (and its Hessian) stays
    small."""
    import casadi as ca

    v = np.asarray(verts, dtype=np.float64)
    if _area2(v) < 0:
        v = v[::-1]
    d2: Any = None  # the least squared distance to an edge so far (CasADi expression)
    line: Any = None  # the largest signed distance to an edge's line so far
    for i in range(len(v)):
        a, e = v[i], v[(i + 1) % len(v)] - v[i]
        di = _clamped_d2(lx, ly, a, e)
        li = ((lx - a[0]) * e[1] - (ly - a[1]) * e[0]) / np.sqrt(float(e @ e))  # to the edge's line, + outside
        d2 = di if d2 is None else ca.fmin(d2, di)
        line = li if line is None else ca.fmax(line, li)
    return ca.if_else(line > 0, ca.sqrt(d2 + 1e-12), line)


def _clamped_d2(lx: Any, ly: Any, a: NDArray[np.float64], e: NDArray[np.float64]) -> Any:
    """Squared distance [mm^2] from ``(lx, ly)`` to the constant segment from ``a`` along ``e`` (2,) [mm]
    (the clamped point-to-segment distance)."""
    import casadi as ca

    rx, ry = lx - a[0], ly - a[1]
    t = ca.fmin(1, ca.fmax(0, (rx * e[0] + ry * e[1]) / float(e @ e)))
    dx, dy = rx - t * e[0], ry - t * e[1]
    return dx * dx + dy * dy


def _area2(v: NDArray[np.float64]) -> float:
    """Twice the signed area of the polygon ``v`` (V, 2) (positive when counter-clockwise)."""
    return float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))


_CACHE: dict[tuple, SwitchNLP] = {}


def _key(tool: Tool, n_knots: int, platform: OmniPlatform, bodies: Sequence[Body], model: str, solver: str,
         smooth: float, reach: bool | tuple[bool, bool, bool], separators: str) -> tuple:
    return (_tool_key(tool), model, n_knots, platform, tuple(b.signature for b in bodies),
            tuple(b.family == "object" for b in bodies), solver, smooth, reach_families(reach), separators)


def get_nlp(tool: Tool, n_knots: int, platform: OmniPlatform, bodies: Sequence[Body], *, model: str = "pieces",
            solver: str = "ipopt", smooth: float = 10.0, reach: bool | tuple[bool, bool, bool] = True,
            separators: str = "distance") -> tuple[SwitchNLP, bool]:
    """The cached NLP for this structure (built on first use); returns ``(nlp, built_now)``."""
    key = _key(tool, n_knots, platform, bodies, model, solver, smooth, reach, separators)
    hit = _CACHE.get(key)
    if hit is not None:
        return hit, False
    nlp = build_nlp(tool, n_knots, platform, bodies, model=model, solver=solver, smooth=smooth, reach=reach,
                    separators=separators)
    nlp.key = key
    _CACHE[key] = nlp
    return nlp, True


def clear_cache() -> None:
    """Forget every built NLP."""
    _CACHE.clear()


def initial_separators(nlp: SwitchNLP, xy_mm: NDArray[np.float64], yaw: NDArray[np.float64],
                       bodies: Sequence[Body]) -> NDArray[np.float64]:
    """Initial separating variables (n_sep, N - 2) for the path ``xy_mm`` (N, 2) [mm] / ``yaw`` (N,):
    for a disc, the unit direction from its centre to the nearest point of the piece; for a polygon,
    the direction between the centres with ``beta`` half way between the two shapes' projections."""
    N = nlp.n_knots
    out = np.zeros((nlp.n_sep, N - 2))
    if nlp.n_sep == 0:
        return out
    c, s = np.cos(yaw[1:-1]), np.sin(yaw[1:-1])
    R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (K, 2, 2)
    for j, bi, off, poly in nlp.sep_layout:
        w = np.einsum("kij,vj->kvi", R, nlp.pieces[j]) + xy_mm[1:-1, None, :]  # (K, V, 2)
        b = bodies[bi]
        if not poly:
            cen = b.data[:2]
            a, e = w, np.roll(w, -1, axis=1) - w
            t = np.clip(np.einsum("kvi,kvi->kv", cen - a, e) / np.maximum(np.einsum("kvi,kvi->kv", e, e), 1e-12), 0, 1)
            near = a + t[..., None] * e
            d = near - cen
            dist = np.hypot(d[..., 0], d[..., 1])
            best = d[np.arange(d.shape[0]), dist.argmin(axis=1)]
            # a centre inside the piece: point away from the piece's centroid
            inside = _inside_convex(w, cen)
            best[inside] = cen - w[inside].mean(axis=1)
            n = best / np.maximum(np.hypot(best[:, 0], best[:, 1]), 1e-12)[:, None]
            if nlp.angle:
                out[off] = np.arctan2(n[:, 1], n[:, 0])
            else:
                out[off:off + 2] = n.T
        else:
            ov = b.data.reshape(-1, 2)
            d = w.mean(axis=1) - ov.mean(axis=0)
            n = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]
            lo = np.einsum("kvi,ki->kv", w, n).min(axis=1)
            hi = (ov @ n.T).max(axis=0)
            if nlp.angle:
                out[off] = np.arctan2(n[:, 1], n[:, 0])
                out[off + 1] = 0.5 * (lo + hi)
            else:
                out[off:off + 2] = n.T
                out[off + 2] = 0.5 * (lo + hi)
    return out


def _inside_convex(w: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether ``p`` (2,) lies inside each convex polygon ``w`` (K, V, 2) (either orientation)."""
    e = np.roll(w, -1, axis=1) - w
    cr = e[..., 0] * (p[1] - w[..., 1]) - e[..., 1] * (p[0] - w[..., 0])
    return np.all(cr >= 0, axis=1) | np.all(cr <= 0, axis=1)
