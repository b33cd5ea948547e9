"""The discrete Dynamic Movement Primitive (paper eqs. 1-5) and its skill file.

A fitted DMP is saved as versioned JSON (:mod:`tooltransfer.versioned_json`), format ``tooltransfer.dmp/1``::

    {"format": "tooltransfer.dmp/1",
     "formulation": "<equations in words>",
     "n_dims", "n_basis", "alpha_z", "beta_z", "gamma", "scaling", "ridge", "fit_method",
     "tau" [s], "x0" [m], "g" [m], "centres", "widths", "weights" (N x n)}

The other skill formats (``tooltransfer.oe/1``, ``tooltransfer.ss/1``) nest this dictionary
(:meth:`DMP.to_dict`, :meth:`DMP.from_dict`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, cast

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from tooltransfer.dmp.affine import AffineRollout
from tooltransfer.dmp.basis import DEFAULT_GAMMA, basis, centres_and_widths, phase
from tooltransfer.dmp.exact import RESPONSE_CACHE, SystemParams, free_response
from tooltransfer.dmp.integrate import rk4_rollout
from tooltransfer.dmp.online import DMPState, exact_step
from tooltransfer.dmp.scaling import SCALING_MODES, ScalingMode, scaling_matrix
from tooltransfer.dmp.trajectory import Rollout
from tooltransfer.errors import InputError, SkillFileError
from tooltransfer.validation import check_array, check_positive, check_time
from tooltransfer.versioned_json import check_format, format_tag, read_versioned, write_versioned

FitMethod = Literal["forcing", "trajectory"]

FORMAT = "tooltransfer.dmp"
"""Name of the DMP skill format (its files carry ``"format": "tooltransfer.dmp/1"``)."""
VERSION = 1
"""Version of the DMP skill format this library writes and reads."""
FORMULATION = (
    "tau*dv/dt = alpha_z*(beta_z*(g - x) - v) + f(s); tau*dx/dt = v; tau*ds/dt = -gamma*s; "
    "f(s) = M(x0, g) @ W.T @ psi(s); psi_i = phi_i*s/sum_j phi_j; phi_i = exp(-h_i*(s - c_i)^2)"
)
"""The equations a skill file's parameters belong to, in words (stored in the file for a reader)."""


@dataclass(frozen=True)
class Demo:
    """One validated demonstration: times (T,) [s], positions (T, n) [m], derived quantities."""

    t: NDArray[np.float64]
    x: NDArray[np.float64]
    xd: NDArray[np.float64]
    xdd: NDArray[np.float64]

    @property
    def tau(self) -> float:
        return float(self.t[-1] - self.t[0])

    @property
    def extent(self) -> float:
        return float(np.ptp(self.x, axis=0).max())


class DMP:
    r"""Discrete DMP in ``n_dims`` dimensions with a shared phase.

    Transformation system per dimension (eqs. 1-2) and canonical system (eq. 2):

    $$
    \tau \dot v = \alpha_z(\beta_z(g - x) - v) + f(s), \quad \tau \dot x = v, \quad
    \tau \dot s = -\gamma s,
    $$

    forcing term (eq. 3) ``f(s) = M(x0, g) @ W.T @ psi(s)`` with ``psi`` from :mod:`tooltransfer.dmp.basis`
    and ``M`` the scaling matrix of the chosen mode (:mod:`tooltransfer.dmp.scaling`; the paper prints
    ``"none"``). Fitting (eqs. 4-5) regresses ``W`` on the forcing targets
    ``f_j = tau^2 xdd_j - alpha_z (beta_z (g - x_j) - tau xd_j)`` of all demonstrations at once
    (``method="forcing"``), or on the positions themselves through the exact affine rollout
    (``method="trajectory"``). Each demonstration keeps its own ``tau`` (its duration) and so is
    mapped onto the one phase.

    Args:
        n_dims: number of dimensions n.
        n_basis: number of basis functions N per dimension (>= 1).
        alpha_z: spring-damper gain [-] (default 25).
        beta_z: [-], default ``alpha_z / 4`` (critical damping).
        gamma: phase constant [-]; the default brings the phase to 0.01 at ``t = tau``.
        scaling: forcing-term scaling mode, one of ``"none"``, ``"amplitude"``, ``"similarity"``.
        ridge: ridge regularisation, relative to the mean diagonal of the normal matrix.
    """

    def __init__(
        self,
        n_dims: int,
        n_basis: int = 50,
        alpha_z: float = 25.0,
        beta_z: float | None = None,
        gamma: float = DEFAULT_GAMMA,
        scaling: ScalingMode = "none",
        ridge: float = 1e-8,
    ) -> None:
        if not isinstance(n_dims, int | np.integer) or n_dims < 1:
            raise InputError("n_dims", "an integer >= 1", repr(n_dims))
        if not isinstance(n_basis, int | np.integer) or n_basis < 1:
            raise InputError("n_basis", "an integer >= 1", repr(n_basis))
        if scaling not in SCALING_MODES:
            raise InputError("scaling", f"one of {', '.join(SCALING_MODES)}", repr(scaling))
        if not np.isfinite(ridge) or ridge < 0:
            raise InputError("ridge", "a finite number >= 0", repr(ridge))
        self.n_dims = int(n_dims)
        self.n_basis = int(n_basis)
        self.alpha_z = check_positive(alpha_z, "alpha_z")
        self.beta_z = check_positive(alpha_z / 4.0 if beta_z is None else beta_z, "beta_z")
        self.gamma = check_positive(gamma, "gamma")
        self.scaling: ScalingMode = scaling
        self.ridge = float(ridge)
        self.centres, self.widths = centres_and_widths(self.n_basis, self.gamma)
        self.weights = np.zeros((self.n_basis, self.n_dims))
        self.tau = 1.0
        self.x0 = np.zeros(self.n_dims)
        self.g = np.zeros(self.n_dims)
        self.fit_method: str | None = None

    # ------------------------------------------------------------------ basics
    def params(self, tau: float | None = None) -> SystemParams:
        """The linear-system parameters for duration ``tau`` [s] (default: the fitted one)."""
        return SystemParams(self.n_basis, self.alpha_z, self.beta_z, self.gamma, self.tau if tau is None else tau)

    def basis(self, t_rel: ArrayLike, tau: float | None = None) -> NDArray[np.float64]:
        """Basis values ``psi`` of shape (T, N) at times ``t_rel`` [s] from the start."""
        return basis(phase(np.asarray(t_rel, dtype=np.float64), self.tau if tau is None else tau, self.gamma),
                     self.centres, self.widths)

    def scaling_matrix(self, x0: NDArray[np.float64], g: NDArray[np.float64]) -> NDArray[np.float64]:
        """``M(x0, g)`` (n, n) of this DMP's scaling mode."""
        return scaling_matrix(self.scaling, x0, g)

    def forcing(self, t_rel: ArrayLike, x0: ArrayLike, g: ArrayLike, tau: float | None = None) -> NDArray[np.float64]:
        """Forcing term ``f`` (T, n) at times ``t_rel`` [s] from the start, for start ``x0``, goal ``g``."""
        m = self.scaling_matrix(np.asarray(x0, float), np.asarray(g, float))
        return self.basis(t_rel, tau) @ self.weights @ m.T

    # ------------------------------------------------------------------ fitting
    def _demos(self, t: ArrayLike | Sequence[ArrayLike], x: ArrayLike | Sequence[ArrayLike]) -> list[Demo]:
        multi = isinstance(t, list | tuple)
        if multi != isinstance(x, list | tuple):
            raise InputError("t, X", "both arrays or both lists of the same length")
        ts = cast(list[ArrayLike], list(t) if multi else [t])  # type: ignore[arg-type]
        xs = cast(list[ArrayLike], list(x) if multi else [x])  # type: ignore[arg-type]
        if len(ts) != len(xs) or not ts:
            raise InputError("t, X", "lists of equal, non-zero length", f"{len(ts)} and {len(xs)}")
        demos = []
        for j, (tj, xj) in enumerate(zip(ts, xs, strict=True)):
            suffix = f"[{j}]" if multi else ""
            tt = check_time(tj, f"t{suffix}", min_len=3)
            xx = check_array(xj, f"X{suffix}", shape=(tt.size, self.n_dims))
            xd = np.gradient(xx, tt, axis=0, edge_order=2)
            xdd = np.gradient(xd, tt, axis=0, edge_order=2)
            demos.append(Demo(tt, xx, xd, xdd))
        return demos

    def _solve_ridge(self, a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
        """Ridge least squares ``min |a w - b|^2 + lam |w|^2`` via an augmented QR/SVD solve."""
        col = np.linalg.norm(a, axis=0)
        col[col == 0.0] = 1.0
        a_s = a / col  # whiten columns: the trajectory-space design is badly scaled
        lam = np.sqrt(self.ridge * np.mean(col**2))  # ridge relative to the normal matrix
        aug = np.vstack([a_s, lam * np.diag(1.0 / col)])
        rhs = np.concatenate([b, np.zeros((a.shape[1], *b.shape[1:]))])
        sol = scipy.linalg.lstsq(aug, rhs, lapack_driver="gelsd")[0]
        return sol / (col if sol.ndim == 1 else col[:, None])

    def fit(
        self,
        t: ArrayLike | Sequence[ArrayLike],
        X: ArrayLike | Sequence[ArrayLike],
        *,
        method: FitMethod = "forcing",
    ) -> DMP:
        """Fit the weights to one or several demonstrations (eqs. 4-5).

        Args:
            t: times, shape (T,) [s], or a list of them (demonstrations may differ in length
                and duration).
            X: positions, shape (T, n_dims) [m], or a list matching ``t``.
            method: ``"forcing"`` regresses the forcing targets (eq. 4); ``"trajectory"`` fits the
                positions through the exact affine rollout (each demonstration's start, goal, start
                velocity and duration).
        Returns:
            self, with ``weights`` (N, n), ``tau`` (mean duration), ``x0``/``g`` (mean start/goal).
        """
        if method not in ("forcing", "trajectory"):
            raise InputError("method", "'forcing' or 'trajectory'", repr(method))
        demos = self._demos(t, X)
        extent = max(d.extent for d in demos)
        blocks_a, blocks_b = [], []
        for d in demos:
            x0, g = d.x[0], d.x[-1]
            m = scaling_matrix(self.scaling, x0, g, extent=extent)
            t_rel = d.t - d.t[0]
            if method == "forcing":
                f = d.tau**2 * d.xdd - self.alpha_z * (self.beta_z * (g - d.x) - d.tau * d.xd)
                psi = self.basis(t_rel, d.tau)
                # rows: f_k = M @ W.T @ psi_k  <=>  psi_k @ W = f_k @ inv(M).T
                blocks_a.append(psi)
                blocks_b.append(np.linalg.solve(m, f.T).T)
            else:
                aff = self._affine(t_rel, x0, g, d.xd[0], d.tau, m)
                blocks_a.append(aff.position_matrix())
                blocks_b.append((d.x - aff.x_free).ravel())
        a, b = np.vstack(blocks_a), np.concatenate(blocks_b)
        w = self._solve_ridge(a, b)
        self.weights = w if method == "forcing" else w.reshape(self.n_basis, self.n_dims)
        self.tau = float(np.mean([d.tau for d in demos]))
        self.x0 = np.mean([d.x[0] for d in demos], axis=0)
        self.g = np.mean([d.x[-1] for d in demos], axis=0)
        self.fit_method = method
        return self

    # ------------------------------------------------------------------ rollout
    def _resolve(
        self, x0: ArrayLike | None, g: ArrayLike | None, v0: ArrayLike | None, tau: float | None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]:
        n = (self.n_dims,)
        x0a = self.x0.copy() if x0 is None else check_array(x0, "x0", shape=n)
        ga = self.g.copy() if g is None else check_array(g, "g", shape=n)
        v0a = np.zeros(self.n_dims) if v0 is None else check_array(v0, "v0", shape=n)
        taua = self.tau if tau is None else check_positive(tau, "tau")
        return x0a, ga, v0a, taua

    def _affine(
        self, t_rel: NDArray[np.float64], x0: NDArray[np.float64], g: NDArray[np.float64],
        v0: NDArray[np.float64], tau: float, m: NDArray[np.float64],
    ) -> AffineRollout:
        p = self.params(tau)
        resp = RESPONSE_CACHE.get(p, t_rel, self.centres, self.widths)
        xf, vf = free_response(p, resp.E, x0, g, v0)
        return AffineRollout(t=t_rel, x_free=xf, v_free=vf, Gx=resp.Gx, Gv=resp.Gv, M=m, psi=resp.psi)

    def affine(
        self,
        t: ArrayLike,
        *,
        x0: ArrayLike | None = None,
        g: ArrayLike | None = None,
        v0: ArrayLike | None = None,
        tau: float | None = None,
    ) -> AffineRollout:
        """The affine map weights -> sampled motion on times ``t`` (T,) [s]; the motion starts at ``t[0]``."""
        tt = check_time(t, "t", min_len=2)
        x0a, ga, v0a, taua = self._resolve(x0, g, v0, tau)
        aff = self._affine(tt - tt[0], x0a, ga, v0a, taua, self.scaling_matrix(x0a, ga))
        return dataclasses.replace(aff, t=tt)

    def rollout(
        self,
        t: ArrayLike,
        *,
        x0: ArrayLike | None = None,
        g: ArrayLike | None = None,
        v0: ArrayLike | None = None,
        tau: float | None = None,
        method: Literal["exact", "rk4"] = "exact",
        rk4_step: float = 1e-3,
        weights: ArrayLike | None = None,
    ) -> Rollout:
        """Roll the DMP out on times ``t`` (T,) [s]; the motion starts at ``t[0]``.

        Args:
            x0, g: start and goal (n,) [m]; default: the fitted mean start and goal.
            v0: start velocity (n,) [m/s], honoured exactly; default zero.
            tau: duration [s]; default: the fitted mean duration.
            method: ``"exact"`` (affine map, cached per grid) or ``"rk4"`` (reference).
            rk4_step: largest RK4 step [s].
            weights: override the fitted weights, shape (N, n) or ``(N*n,)``.
        Returns:
            :class:`~tooltransfer.dmp.trajectory.Rollout` with ``t``, ``x``, ``v``, ``a``, each (T, n) but ``t``.
        """
        tt = check_time(t, "t", min_len=2)
        x0a, ga, v0a, taua = self._resolve(x0, g, v0, tau)
        w = self.weights if weights is None else self._check_weights(weights)
        m = self.scaling_matrix(x0a, ga)
        t_rel = tt - tt[0]
        if method == "exact":
            aff = self._affine(t_rel, x0a, ga, v0a, taua, m)
            x, v = aff.positions(w), aff.velocities(w)
            f = aff.psi @ w @ m.T
        elif method == "rk4":
            check_positive(rk4_step, "rk4_step")

            def forcing(tr: float) -> NDArray[np.float64]:
                return (self.basis(np.array([tr]), taua) @ w @ m.T)[0]

            x, v = rk4_rollout(tt, x0a, ga, v0a, taua, self.alpha_z, self.beta_z, forcing, rk4_step)
            f = self.basis(t_rel, taua) @ w @ m.T
        else:
            raise InputError("method", "'exact' or 'rk4'", repr(method))
        a = (self.alpha_z * (self.beta_z * (ga - x) - taua * v) + f) / taua**2
        return Rollout(t=tt, x=x, v=v, a=a)

    # ------------------------------------------------------------------ online
    def start(
        self,
        *,
        x0: ArrayLike | None = None,
        g: ArrayLike | None = None,
        v0: ArrayLike | None = None,
        tau: float | None = None,
    ) -> DMPState:
        """The state at the start of a stepwise run (:meth:`step`); defaults as in :meth:`rollout`."""
        x0a, ga, v0a, taua = self._resolve(x0, g, v0, tau)
        return DMPState(t=0.0, x=x0a.copy(), v=v0a, x0=x0a, g=ga, tau=taua)

    def step(
        self,
        state: DMPState,
        dt: float,
        *,
        goal: ArrayLike | None = None,
        coupling: ArrayLike | None = None,
    ) -> DMPState:
        r"""Advance a run by one control period: stepwise execution (:mod:`tooltransfer.dmp.online`).

        Integrates $\tau^2 \ddot x = \alpha_z(\beta_z(g - x) - \tau \dot x) + f(s) + C$ exactly
        over ``dt`` with the goal and the coupling term held; with no coupling and a fixed goal the
        states agree with :meth:`rollout` on the same times to round-off, however the steps are cut.

        Args:
            state: the run's state, from :meth:`start` or a previous step.
            dt: the step [s], > 0.
            goal: a new goal (n,) [m] from this step on (a moving goal); default: the one in force.
            coupling: the coupling term ``C`` (n,) [m] for this step (obstacle avoidance, for
                instance :func:`tooltransfer.dmp.coupling.obstacle_coupling`); default zero.
        Returns:
            The state at ``state.t + dt``, carrying the goal in force.
        """
        dta = check_positive(dt, "dt")
        n = (self.n_dims,)
        if goal is not None:
            state = dataclasses.replace(state, g=check_array(goal, "goal", shape=n))
        c = np.zeros(self.n_dims) if coupling is None else check_array(coupling, "coupling", shape=n)
        return exact_step(self.params(state.tau), self.centres, self.widths, self.weights, self.scaling,
                          state, dta, c)

    def _check_weights(self, weights: ArrayLike) -> NDArray[np.float64]:
        w = check_array(weights, "weights")
        if w.size != self.n_basis * self.n_dims:
            raise InputError("weights", f"{self.n_basis * self.n_dims} values (N x n)", f"shape {w.shape}")
        return w.reshape(self.n_basis, self.n_dims)

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        """Plain-data description, format ``tooltransfer.dmp/1`` (JSON-serialisable; module docstring)."""
        return {
            "format": format_tag(FORMAT, VERSION),
            "formulation": FORMULATION,
            "n_dims": self.n_dims,
            "n_basis": self.n_basis,
            "alpha_z": self.alpha_z,
            "beta_z": self.beta_z,
            "gamma": self.gamma,
            "scaling": self.scaling,
            "ridge": self.ridge,
            "fit_method": self.fit_method,
            "tau": self.tau,
            "x0": self.x0.tolist(),
            "g": self.g.tolist(),
            "centres": self.centres.tolist(),
            "widths": self.widths.tolist(),
            "weights": self.weights.tolist(),
        }

    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> DMP:
        """Rebuild a DMP from :meth:`to_dict` output; another format or version, a missing field or
        damaged values raise :class:`~tooltransfer.errors.SkillFileError` naming ``source``."""
        check_format(data, FORMAT, VERSION, source)
        try:
            d = cls(
                n_dims=int(data["n_dims"]),
                n_basis=int(data["n_basis"]),
                alpha_z=float(data["alpha_z"]),
                beta_z=float(data["beta_z"]),
                gamma=float(data["gamma"]),
                scaling=data["scaling"],
                ridge=float(data["ridge"]),
            )
            w = np.asarray(data["weights"], dtype=np.float64)
            if w.shape != (d.n_basis, d.n_dims) or not np.all(np.isfinite(w)):
                raise SkillFileError(
                    source, f"'weights' must be finite with shape ({d.n_basis}, {d.n_dims}), got {w.shape}"
                )
            for key in ("centres", "widths"):
                stored = np.asarray(data[key], dtype=np.float64)
                expect = d.centres if key == "centres" else d.widths
                if stored.shape != expect.shape or not np.allclose(stored, expect, rtol=1e-12, atol=0):
                    raise SkillFileError(source, f"'{key}' disagree with n_basis and gamma (corrupted file?)")
            d.weights = w
            d.tau = float(data["tau"])
            d.x0 = np.asarray(data["x0"], dtype=np.float64).reshape(d.n_dims)
            d.g = np.asarray(data["g"], dtype=np.float64).reshape(d.n_dims)
            d.fit_method = data.get("fit_method")
        except KeyError as exc:
            raise SkillFileError(source, f"missing field {exc.args[0]!r}") from exc
        except (TypeError, ValueError, InputError) as exc:
            raise SkillFileError(source, f"invalid value: {exc}") from exc
        return d

    def save(self, path: str | Path) -> None:
        """Save the skill as a versioned JSON file (:meth:`to_dict`), atomically
        (:func:`tooltransfer.versioned_json.write_versioned`)."""
        write_versioned(path, self.to_dict(), indent=1)

    @classmethod
    def load(cls, path: str | Path) -> DMP:
        """Load a skill saved by :meth:`save`; a missing or damaged file or another format raises
        :class:`~tooltransfer.errors.SkillFileError`."""
        return cls.from_dict(read_versioned(path, FORMAT, VERSION), str(path))
