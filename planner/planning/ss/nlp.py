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

The rows of one knot are built in :mod:`tooltransfer.planner.planning.ss.switch_rows`, the initial separators
of a start path in :mod:`tooltransfer.planner.planning.ss.separator_guess`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from tooltransfer.errors import InputError
from tooltransfer.planner.planning.ss.bodies import Body
from tooltransfer.planner.planning.ss.knot_rows import KnotRows, placed, triplet
from tooltransfer.planner.planning.ss.switch_rows import (
    Capsule,
    InteriorKnot,
    ToolRows,
    body_rows,
    reach_families,
    reach_rows,
)
from tooltransfer.tools.model import Tool
from tooltransfer.tools.omni.platform import OmniPlatform


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
    tr = ToolRows.of(tool, bodies, model, separators)
    n_vars = 2 * N + K * tr.n_sep
    sizes = [int(b.data.size) for b in bodies]
    n_params = 4 * N + sum(sizes) + 1
    z, p = ca.MX.sym("z", n_vars), ca.MX.sym("p", n_params)
    # one knot's variables: its centre, then its separators (z's order: knot k is column k + 1 of X)
    var_index = np.column_stack([2 * np.arange(1, N - 1), 2 * np.arange(1, N - 1) + 1,
                                 2 * N + tr.n_sep * np.arange(K)[:, None] + np.arange(tr.n_sep)]).astype(np.intp)
    v = ca.SX.sym("v", 2 + tr.n_sep)
    m = ca.SX.sym("m")
    knot = InteriorKnot(v[:2], platform)
    S = v[2:] if tr.n_sep else None
    interior = KnotRows(var_index, n_vars)
    families: list[tuple[str, int, int]] = []
    count, off = 0, 4 * N
    for bi, (b, size) in enumerate(zip(bodies, sizes, strict=True)):
        q = ca.SX.sym(f"body{bi}", size)
        base = 2 * N if b.family == "object" else 3 * N  # m_obj or m_obs, at the interior knots
        margins = p[base + 1:base + N - 1].T
        n = interior.add(f"body{bi}", v, q, m, body_rows(knot, tr, b, bi, q, m, S), p[off:off + size], margins)
        families.append((b.family, count, count + n))
        count, off = count + n, off + size
    start = count
    per_knot = reach_rows(knot, platform, reach, reach_margin)
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
