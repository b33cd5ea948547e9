"""Identification of the push model's parameters ``mu`` and ``c`` from recorded pushes (docs/design.md section 10).

The paper's Assumption 1 leaves the object's and the contact's properties to "parameter
identification methods"; here they are fitted by least squares of the forward model
(:mod:`tooltransfer.tools.pushing.forward`) to what the sensors recorded:

* **Data.** Per push (:class:`RecordedPush`) the tool poses from the encoders over the push, the
  camera's samples of the puck over the push and a short rest after it, and the puck's rest
  positions before and after the push (means of the camera frames of the resting puck).
* **Residuals.** The forward model runs the recorded tool poses from the rest position before the
  push; its puck track, interpolated linearly to the camera's times (and held at its last value
  after the last tool sample: the puck rests once the tool leaves it), minus the camera's
  positions, both axes, every camera sample [m].
* **Fit.** :func:`scipy.optimize.least_squares` (trust region reflective) in ``(log mu, log c)``
  with bounds ``mu`` in (0.05, 5), ``c`` in (0.2, 1.5), forward-difference Jacobian, plus a weak
  prior that pulls each log towards the initial value with standard deviation ``prior_sd`` (1 by
  default: a factor e): it keeps a parameter the pushes do not excite near its initial value
  instead of letting it drift with the noise, and moves an excited one by less than 1e-3 of its
  standard deviation.
* **Uncertainty.** ``cov = (J^T J / s^2 + I / prior_sd^2)^-1`` in the logs, ``J`` the data rows of
  the Jacobian at the solution, ``s^2`` the residual variance (sum of squares over ``N - 2``), gives
  ``sd(mu) = mu sd(log mu)`` (delta method), the same for ``c`` (:attr:`Identification.plain_std`).
  That assumes independent residuals; the camera's noise is, but an error of a rest position (or
  of the model) is shared by every sample of one push, so the cluster-robust (sandwich, clustered
  by push) deviations are computed too (:attr:`Identification.robust_std`). The mechanics carry
  the larger of the two. Measured on synthetic pushes (27 per fit, 16 fits): with exact rest
  positions the plain deviations are right (RMS z-score 1.1 for mu, 1.0 for c); with rest positions
  from 20 camera samples (0.33 mm) they are too small (RMS z 1.5 and 2.0), the larger of the two
  less so (1.2 and 1.5).
* **Excitation.** A parameter counts as identified when the data alone pin its log to within
  ``excitation_tol`` (one standard deviation, 0.25 by default). ``c`` enters only through the
  puck's motion across the contact normal, so pushes along the normal do not excite it; ``mu``
  enters only when the contact slides (``|tan phi_p| > mu (1 + 1/c^2)``, about 72 degrees off the
  normal with the platform's values), so pushes that stick do not excite it. A parameter not
  excited keeps its initial value exactly (the prior holds it within noise of it anyway) and is
  reported through a large standard deviation (the prior's) and a message, not an error.

Speed: all pushes run in one :func:`tooltransfer.tools.pushing.forward.simulate_batch` call (shorter ones padded
by repeating their last pose, which moves nothing) with substeps of at most ``max_step`` = 0.2 mm
(end positions within 0.02 mm of 0.02 mm substeps, far below the camera's noise); about 12
evaluations of the model, see ``tests/test_pushing_identify.py`` and the README for timings.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError
from tooltransfer.tools.model import Tool
from tooltransfer.tools.pushing.forward import simulate_batch
from tooltransfer.tools.pushing.mechanics import PLATFORM_MECHANICS, PushMechanics
from tooltransfer.validation import check_array, check_positive, check_time

#: Bounds of the fit (mu, c).
MU_BOUNDS, C_BOUNDS = (0.05, 5.0), (0.2, 1.5)
#: Substep bound [m] of the forward model during the fit.
MAX_STEP = 2e-4
#: Standard deviation of the weak prior on ``log mu`` and ``log c`` about the initial values.
PRIOR_SD = 1.0
#: Largest standard deviation of a log parameter, from the data alone, for it to count as identified.
EXCITATION_TOL = 0.25
#: Relative finite-difference step of the Jacobian (in the logs): well above the forward model's
#: rounding (its overlap tests resolve 1e-13 m) and well below the parameters' uncertainty.
DIFF_STEP = 1e-4


@dataclass(frozen=True)
class RecordedPush:
    """One recorded push (world frame, SI units).

    Attributes:
        t_tool: (K,) encoder times [s], strictly increasing, K >= 2: from before the tool meets the
            puck until the push ends (the puck is taken to rest after the last sample).
        tool_pose: (K, 3) tool poses ``x, y`` [m], ``yaw`` [rad] (unwrapped on construction).
        t_object: (M,) camera times [s], strictly increasing, M >= 1: the push and a short rest after it.
        object_xy: (M, 2) the camera's puck centres [m] at those times (noisy).
        object_start: (2,) the puck's rest position before the push [m] (where the model starts it).
        object_end: (2,) the puck's rest position after the push [m] (the mean of the camera frames
            of the resting puck; only for the end-position error).
        name: a label for reports and error messages.
    """

    t_tool: NDArray[np.float64]
    tool_pose: NDArray[np.float64]
    t_object: NDArray[np.float64]
    object_xy: NDArray[np.float64]
    object_start: NDArray[np.float64]
    object_end: NDArray[np.float64]
    name: str = "push"

    def __post_init__(self) -> None:
        n = self.name
        t = check_time(self.t_tool, f"{n}.t_tool", min_len=2)
        pose = check_array(self.tool_pose, f"{n}.tool_pose", shape=(t.size, 3)).copy()
        pose[:, 2] = np.unwrap(pose[:, 2])
        to = check_time(self.t_object, f"{n}.t_object", min_len=1)
        for key, value in (("t_tool", t), ("tool_pose", pose), ("t_object", to),
                           ("object_xy", check_array(self.object_xy, f"{n}.object_xy", shape=(to.size, 2))),
                           ("object_start", check_array(self.object_start, f"{n}.object_start", shape=(2,))),
                           ("object_end", check_array(self.object_end, f"{n}.object_end", shape=(2,)))):
            object.__setattr__(self, key, value)


def rest_position(t_object: ArrayLike, object_xy: ArrayLike, t0: float, t1: float,
                  field: str = "rest") -> NDArray[np.float64]:
    """The puck's rest position (2,) [m]: the mean of the camera samples ``object_xy`` (M, 2) [m]
    at times ``t_object`` (M,) [s] within ``[t0, t1]`` (the puck at rest, so the camera's noise
    averages out as ``1 / sqrt(n)``). Raises :class:`InputError` naming ``field`` without samples."""
    t = check_array(t_object, f"{field}.t_object", ndim=1)
    xy = check_array(object_xy, f"{field}.object_xy", shape=(t.size, 2))
    m = (t >= t0) & (t <= t1)
    if not np.any(m):
        raise InputError(field, f"camera samples of the resting puck within [{t0:.3f}, {t1:.3f}] s", 0)
    return xy[m].mean(axis=0)


@dataclass(frozen=True)
class Identification:
    """The identified push model and how well it explains the recordings.

    Attributes:
        mechanics: ``mu``, ``c`` with ``mu_std``, ``c_std`` (one sigma: the larger of
            :attr:`plain_std` and :attr:`robust_std`), ``source="identified"``.
        initial: the mechanics the fit started from (and the prior's centre).
        names: (P,) the pushes' labels.
        residual_rms: (P,) per push, RMS [m] of the distance between the predicted and the camera's
            puck over its samples.
        end_error: (P,) per push, distance [m] between the predicted end position and the recorded
            rest position after the push.
        end_error_initial: (P,) the same with the initial mechanics.
        n_samples: camera samples used (each gives two residuals).
        cost: half the sum of squared residuals [m^2] at the solution (data only).
        sigma: the residual standard deviation per axis [m].
        data_std: (2,) standard deviations of ``log mu`` and ``log c`` from the data alone (inf when
            the data say nothing).
        plain_std: (2,) standard deviations of ``mu`` and ``c`` from the Jacobian (independent residuals).
        robust_std: (2,) cluster-robust (sandwich, clustered by push) standard deviations of ``mu``
            and ``c``: they allow for errors shared within a push (a rest position, the model).
        mu_excited, c_excited: whether the pushes identify each parameter (``data_std`` below the
            excitation tolerance).
        message: why a parameter is not identified ("" when both are).
        n_evaluations: forward-model runs (each simulates every push); wall_time: seconds.
    """

    mechanics: PushMechanics
    initial: PushMechanics
    names: tuple[str, ...]
    residual_rms: NDArray[np.float64]
    end_error: NDArray[np.float64]
    end_error_initial: NDArray[np.float64]
    n_samples: int
    cost: float
    sigma: float
    data_std: NDArray[np.float64]
    plain_std: NDArray[np.float64]
    robust_std: NDArray[np.float64]
    mu_excited: bool
    c_excited: bool
    message: str = ""
    n_evaluations: int = 0
    wall_time: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def n_pushes(self) -> int:
        """Number of pushes fitted."""
        return len(self.names)

    def summary(self) -> dict[str, Any]:
        """JSON-ready scalars: the parameters, their uncertainty, the fit's figures [m] and flags."""
        e = self.end_error
        return {
            **self.mechanics.to_dict(),
            "mu_std_plain": float(self.plain_std[0]), "c_std_plain": float(self.plain_std[1]),
            "mu_std_robust": float(self.robust_std[0]), "c_std_robust": float(self.robust_std[1]),
            "mu_excited": self.mu_excited, "c_excited": self.c_excited, "message": self.message,
            "n_pushes": self.n_pushes, "n_samples": self.n_samples, "sigma": self.sigma, "cost": self.cost,
            "residual_rms_median": float(np.median(self.residual_rms)),
            "end_error_median": float(np.median(e)), "end_error_p90": float(np.percentile(e, 90)),
            "end_error_max": float(e.max()),
            "end_error_initial_median": float(np.median(self.end_error_initial)),
            "initial": self.initial.to_dict(), "n_evaluations": self.n_evaluations, "wall_time": self.wall_time,
            **self.extra,
        }

    def to_dict(self) -> dict[str, Any]:
        """Everything as plain JSON data (:meth:`from_dict` reads it back; an infinite deviation is null)."""
        out: dict[str, Any] = {"summary": self.summary(), "names": list(self.names)}
        for key in _ARRAYS:
            out[key] = [None if not np.isfinite(v) else float(v) for v in getattr(self, key)]
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any], field: str = "identification") -> Identification:
        """From :meth:`to_dict` output; raises :class:`InputError` naming ``field`` on a bad document."""
        try:
            s = data["summary"]
            arrays = {k: np.array([np.inf if v is None else v for v in data[k]], dtype=np.float64) for k in _ARRAYS}
            return cls(
                mechanics=PushMechanics.from_dict(s, f"{field}.summary"),
                initial=PushMechanics.from_dict(s["initial"], f"{field}.summary.initial"),
                names=tuple(str(n) for n in data["names"]), **arrays, n_samples=int(s["n_samples"]),
                cost=float(s["cost"]), sigma=float(s["sigma"]), mu_excited=bool(s["mu_excited"]),
                c_excited=bool(s["c_excited"]), message=str(s["message"]), n_evaluations=int(s["n_evaluations"]),
                wall_time=float(s["wall_time"]), extra={k: v for k, v in s.items() if k not in _SUMMARY_KEYS})
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise InputError(field, "an identification document (Identification.to_dict)", repr(exc)) from None


_ARRAYS = ("residual_rms", "end_error", "end_error_initial", "data_std", "plain_std", "robust_std")
_SUMMARY_KEYS = frozenset({
    "mu", "c", "source", "mu_std", "c_std", "mu_std_plain", "c_std_plain", "mu_std_robust", "c_std_robust",
    "mu_excited", "c_excited", "message", "n_pushes", "n_samples", "sigma", "cost", "residual_rms_median",
    "end_error_median", "end_error_p90", "end_error_max", "end_error_initial_median", "initial", "n_evaluations",
    "wall_time"})
"""Keys :meth:`Identification.summary` writes itself (others come from ``extra``)."""


@dataclass(frozen=True)
class _Batch:
    """The pushes packed for :func:`simulate_batch` and the camera samples' interpolation weights."""

    poses: NDArray[np.float64]  # (B, K, 3), padded by repeating the last pose
    start: NDArray[np.float64]  # (B, 2)
    last: NDArray[np.intp]  # (B,) index of each push's last real sample
    run: NDArray[np.intp]  # (N,) push of each camera sample
    i0: NDArray[np.intp]  # (N,) tool sample at or before the camera time (clamped)
    w: NDArray[np.float64]  # (N,) weight of sample i0 + 1
    observed: NDArray[np.float64]  # (N, 2)

    @classmethod
    def of(cls, pushes: Sequence[RecordedPush]) -> _Batch:
        k_max = max(p.t_tool.size for p in pushes)
        poses = np.empty((len(pushes), k_max, 3))
        run, i0, w = [], [], []
        for b, p in enumerate(pushes):
            k = p.t_tool.size
            poses[b, :k], poses[b, k:] = p.tool_pose, p.tool_pose[-1]
            j = np.clip(np.searchsorted(p.t_tool, p.t_object, side="right") - 1, 0, k - 2)
            frac = (p.t_object - p.t_tool[j]) / (p.t_tool[j + 1] - p.t_tool[j])
            run.append(np.full(p.t_object.size, b))
            i0.append(j)
            w.append(np.clip(frac, 0.0, 1.0))
        return cls(poses, np.array([p.object_start for p in pushes]),
                   np.array([p.t_tool.size - 1 for p in pushes]), np.concatenate(run), np.concatenate(i0),
                   np.concatenate(w), np.concatenate([p.object_xy for p in pushes]))

    def predict(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        """The model's puck (N, 2) [m] at the camera's times from the simulated tracks ``xy`` (B, K, 2)."""
        w = self.w[:, None]
        return (1.0 - w) * xy[self.run, self.i0] + w * xy[self.run, self.i0 + 1]


def _check_inputs(tool: Tool, radius: float, pushes: Sequence[RecordedPush], initial: PushMechanics) -> float:
    if not isinstance(tool, Tool):
        raise InputError("tool", "a tooltransfer.tools.model.Tool", type(tool).__name__)
    r = check_positive(radius, "radius")
    if isinstance(pushes, RecordedPush) or not isinstance(pushes, Sequence) or len(pushes) == 0:
        raise InputError("pushes", "a non-empty sequence of RecordedPush", type(pushes).__name__)
    for i, p in enumerate(pushes):
        if not isinstance(p, RecordedPush):
            raise InputError(f"pushes[{i}]", "a RecordedPush", type(p).__name__)
    if not isinstance(initial, PushMechanics):
        raise InputError("initial", "a PushMechanics", type(initial).__name__)
    for name, v, (lo, hi) in (("mu", initial.mu, MU_BOUNDS), ("c", initial.c, C_BOUNDS)):
        if not lo < v < hi:
            raise InputError(f"initial.{name}", f"a value inside the fit's bounds ({lo}, {hi})", v)
    return r


def _marginal_std(info: NDArray[np.float64]) -> NDArray[np.float64]:
    """Standard deviations (2,) of a 2x2 information matrix's inverse (inf where it is singular)."""
    out = np.full(2, np.inf)
    for i in range(2):
        j = 1 - i
        schur = info[i, i] - (info[i, j] ** 2 / info[j, j] if info[j, j] > 0 else 0.0)
        if schur > 1e-12 * max(info[i, i], 1e-300):
            out[i] = 1.0 / np.sqrt(schur)
    return out


def _not_excited_message(mu_ok: bool, c_ok: bool, data_std: NDArray[np.float64], mech: PushMechanics) -> str:
    parts = []
    if not c_ok:
        parts.append(f"c is not excited by these pushes (the data alone give log c +- {data_std[1]:.3g}: pushes "
                     f"near the face's normal do not move the puck across it); it keeps its initial value "
                     f"c = {mech.c:.3g} (+- {mech.c_std:.3g})")
    if not mu_ok:
        parts.append(f"mu is not excited by these pushes (the data alone give log mu +- {data_std[0]:.3g}: the "
                     f"contacts stick, and mu only acts when they slide, |tan phi_p| > mu (1 + 1/c^2)); it keeps "
                     f"its initial value mu = {mech.mu:.3g} (+- {mech.mu_std:.3g})")
    if parts:
        parts.append("record a calibration (tooltransfer demos --calibration, README) to identify it")
    return "; ".join(parts)


def identify_mechanics(
    tool: Tool, radius: float, pushes: Sequence[RecordedPush], *, initial: PushMechanics = PLATFORM_MECHANICS,
    max_step: float = MAX_STEP, prior_sd: float = PRIOR_SD, excitation_tol: float = EXCITATION_TOL,
) -> Identification:
    """Fit ``mu`` and ``c`` to recorded pushes (method in the module docstring).

    Args:
        tool: the tool the pushes were made with (its outline is the pusher).
        radius: the puck's radius [m].
        pushes: the recorded pushes (at least one).
        initial: where the fit starts and the prior's centre (inside the bounds).
        max_step: substep bound [m] of the forward model.
        prior_sd: standard deviation of the prior on ``log mu`` and ``log c`` (``inf``: none).
        excitation_tol: largest data-only standard deviation of a log parameter to count as identified.

    Returns:
        The :class:`Identification`; a parameter the pushes do not excite is flagged, not an error.
    """
    from scipy.optimize import least_squares  # here: reading a stored identification needs no scipy.optimize

    t_wall = time.perf_counter()
    r = _check_inputs(tool, radius, pushes, initial)
    h = check_positive(max_step, "max_step")
    sd_prior = check_positive(prior_sd, "prior_sd")
    tol = check_positive(excitation_tol, "excitation_tol")
    batch = _Batch.of(pushes)
    n_obs = batch.observed.shape[0]
    x0 = np.log([initial.mu, initial.c])
    memo: dict[bytes, tuple[NDArray[np.float64], NDArray[np.float64]]] = {}

    def run(x: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Data residuals (2N,) [m] and the simulated tracks (B, K, 2) at logs ``x`` (memoised)."""
        key = np.asarray(x, dtype=np.float64).tobytes()
        if key not in memo:
            mu, c = np.exp(x)
            xy = simulate_batch(tool, batch.poses, batch.start, r, PushMechanics(float(mu), float(c)), max_step=h)[0]
            if len(memo) >= 4:  # the point and its finite-difference neighbours
                memo.pop(next(iter(memo)))
            memo[key] = ((batch.predict(xy) - batch.observed).ravel(), xy)
            counter[0] += 1
        return memo[key]

    counter = [0]
    res0, xy0 = run(x0)
    scale = float(np.sqrt(np.mean(res0**2)))  # the prior's rows in residual units (about the noise)

    def fun(x: NDArray[np.float64]) -> NDArray[np.float64]:
        data = run(x)[0]
        return np.concatenate([data, scale * (x - x0) / sd_prior])

    lo = np.log([MU_BOUNDS[0], C_BOUNDS[0]])
    hi = np.log([MU_BOUNDS[1], C_BOUNDS[1]])
    sol = least_squares(fun, x0, jac="2-point", bounds=(lo, hi), method="trf", diff_step=DIFF_STEP,
                        x_scale=1.0, xtol=1e-5, ftol=1e-6, gtol=1e-10)
    res, xy = run(sol.x)
    jac = sol.jac[: 2 * n_obs]
    dof = max(2 * n_obs - 2, 1)
    s2 = float(res @ res) / dof
    info = jac.T @ jac / s2
    data_std = _marginal_std(info)
    post = np.linalg.inv(info + np.eye(2) / sd_prior**2)
    post_std = np.sqrt(np.diag(post))
    # cluster-robust (sandwich) covariance, clustered by push, of the same estimate (the prior's
    # information counted as its own cluster, so a parameter the data do not excite keeps its spread)
    meat = np.eye(2) / sd_prior**2
    rows = np.repeat(batch.run, 2)
    for b in range(len(pushes)):
        m = rows == b
        g = jac[m].T @ res[m] / s2
        meat += np.outer(g, g)
    robust = post @ meat @ post
    mu_ok, c_ok = bool(data_std[0] < tol), bool(data_std[1] < tol)
    x = np.where([mu_ok, c_ok], sol.x, x0)  # a parameter not excited keeps its initial value exactly
    if not np.array_equal(x, sol.x):
        res, xy = run(x)
    mu, c = (float(v) for v in np.exp(x))
    plain_std = np.array([mu, c]) * post_std
    robust_std = np.array([mu, c]) * np.sqrt(np.clip(np.diag(robust), 0.0, None))
    std = np.maximum(plain_std, robust_std)
    mech = PushMechanics(mu, c, "identified", float(std[0]), float(std[1]))
    d = (batch.predict(xy) - batch.observed)
    per = np.bincount(batch.run, weights=np.sum(d**2, axis=1), minlength=len(pushes))
    counts = np.bincount(batch.run, minlength=len(pushes))
    ends = np.array([p.object_end for p in pushes])
    rows_b = np.arange(len(pushes))
    return Identification(
        mechanics=mech, initial=initial, names=tuple(p.name for p in pushes),
        residual_rms=np.sqrt(per / np.maximum(counts, 1)),
        end_error=np.hypot(*(xy[rows_b, batch.last] - ends).T),
        end_error_initial=np.hypot(*(xy0[rows_b, batch.last] - ends).T),
        n_samples=n_obs, cost=0.5 * float(res @ res), sigma=float(np.sqrt(s2)), data_std=data_std,
        plain_std=plain_std, robust_std=robust_std,
        mu_excited=mu_ok, c_excited=c_ok, message=_not_excited_message(mu_ok, c_ok, data_std, mech),
        n_evaluations=counter[0], wall_time=time.perf_counter() - t_wall)
