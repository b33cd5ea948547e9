"""Constraints of a push on the Omni, as constraint families of the constrained DMP fit.

* :class:`HeadingCone`: the object's velocity inside the pushing face's cone, whose direction turns
  with the tool heading (which follows the Omni's waist, hence the object's position): the rows
  are linearised at the current path and re-built in the sequential loop (family ``"cone"``).
* :func:`reach_constraints`: the object positions from which the face can push it lie in an
  annular sector about the joint-1 axis (:mod:`tooltransfer.planner.planning.oe.face_frame`); its two straight sides are
  exact half-planes, its outer arc is replaced by chords inside it and its inner arc by a tangent
  half-plane linearised at the current path (conservative), family ``"reach"``.
* :class:`ContactOnFace`: the contact stays on the face's usable segment while the object moves
  (docs/design.md section 10): sticking, the contact rolls along the face by ``1/c^2`` times the object's
  sideways travel in the face frame and by ``R`` per radian the heading turns, a condition on the
  object's positions over the push, linearised at the current path (family ``"contact"``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.qp.constraints import OutsideDisc, PositionPolygon, cone_rows
from tooltransfer.dmp.qp.constraints.base import Coefficients, Constraint
from tooltransfer.errors import InputError
from tooltransfer.planner.planning.oe.face_frame import FaceFrame
from tooltransfer.tools.pose import wrap_angle
from tooltransfer.tools.pushing.inverse import FaceGeometry
from tooltransfer.tools.pushing.mechanics import PushMechanics

OffsetSeries = tuple[NDArray[np.float64], NDArray[np.float64]]
"""A realised push's times (M,) [s] and the object's offsets (M,) [m] from the arm's plane then."""


class HeadingCone(Constraint):
    """Velocity in the cone of half-angle ``theta_b`` about the face's world push direction, which
    depends on the object's position through the Omni's heading (``frame.push_direction``).

    The rows at each sample use the direction at the linearisation path; evaluated on the path
    itself they measure the true violation [m/s].

    The heading depends on where the contact is on the face too, through the object's ``offset``
    from the arm's plane (:class:`~.face_frame.FaceFrame`): the frame's is that of its own contact.
    ``offsets``: for realised pushes (their contacts where they were, :func:`realised_offsets`), the
    times (M,) [s] and the object's offsets (M,) [m], interpolated on the samples' times; the rows then
    keep the velocity inside the cones at every one of those headings (their intersection: a fit
    that moves the contacts again keeps the cones of the contacts it had).
    """

    linearised = True
    conservative = False

    def __init__(self, frame: FaceFrame, *, family: str = "cone", window: tuple[float, float] | None = None,
                 offsets: Sequence[OffsetSeries] = ()) -> None:
        super().__init__(family, window)
        self.frame = frame
        self.offsets = tuple(offsets)

    def cone(self, t: NDArray[np.float64], x: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The cone's world middle direction [rad] (K,) and half-width [rad] (K,) with the object at ``x``
        (K, 2) [m] at times ``t`` (K,) [s]. Each realised push's offsets apply within its own times (a
        sample two pushes share, at a re-contact, keeps both cones); a sample no push covers keeps the
        frame's heading. Where the cones do not overlap the half-width is negative (the rows would then
        admit the reversed cone: :meth:`empty` tells the caller)."""
        x = np.atleast_2d(x)
        if not self.offsets:
            return self.frame.push_direction(x), np.full(len(x), self.frame.theta_b)
        d = x - self.frame.base
        r2 = np.einsum("ij,ij->i", d, d)
        polar = np.arctan2(d[:, 1], d[:, 0])

        def turn(off: NDArray[np.float64] | float, rr: NDArray[np.float64]) -> NDArray[np.float64]:
            return -np.arctan2(off, np.sqrt(np.maximum(rr - np.square(off), 1e-18)))

        own = turn(self.frame.offset, r2)
        rel = np.full((len(self.offsets), len(x)), np.nan)
        for i, (times, values) in enumerate(self.offsets):
            k = np.flatnonzero((t >= times[0] - 1e-9) & (t <= times[-1] + 1e-9))
            rel[i, k] = own[k] + wrap_angle(turn(np.interp(t[k], times, values), r2[k]) - own[k])
        none = np.isnan(rel).all(axis=0)
        rel[:, none] = own[none]
        lo, hi = np.nanmax(rel, axis=0) - self.frame.theta_b, np.nanmin(rel, axis=0) + self.frame.theta_b
        return polar - np.pi / 2 + self.frame.push_angle + 0.5 * (lo + hi), 0.5 * (hi - lo)

    def empty(self, t: NDArray[np.float64], x: NDArray[np.float64]) -> bool:
        """Whether the cones of the realised pushes fail to overlap at some sample of its window among
        times ``t`` (T,) [s] with the object at ``x`` (T, 2) [m]."""
        k = self.samples(t)
        return bool(k.size) and bool((self.cone(t[k], x[k])[1] < 0.0).any())

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        if x_lin.shape[1] != 2:
            raise InputError("HeadingCone", "a planar (2-D) motion", f"{x_lin.shape[1]}-D")
        middle, half = self.cone(t[k], x_lin[k])
        # where the realised cones do not overlap (the path moved since :meth:`empty` was asked), a hairline
        # cone: negative half-widths would make the rows admit the reversed cone
        a_vel = cone_rows(middle, np.maximum(half, 1e-6))  # (K, 2, 2)
        return Coefficients(k, None, a_vel, np.zeros((k.size, 2)))

    def angle_violation(self, x: NDArray[np.float64], v: NDArray[np.float64], speed_tol: float = 1e-6) -> float:
        """Largest angle [rad] by which the velocity leaves the frame's cone at the frame's own heading
        (without the realised ``offsets``), over samples moving faster than ``speed_tol`` [m/s] (x, v of
        shape (K, 2) at the constraint's samples)."""
        return cone_excess(v, lambda moving: self.frame.push_direction(x[moving]), self.frame.theta_b, speed_tol)


def cone_excess(v: NDArray[np.float64], middle: Callable[[NDArray[np.bool_]], NDArray[np.float64]],
                theta_b: float, speed_tol: float) -> float:
    """Largest angle [rad] by which the velocities ``v`` (K, 2) [m/s] faster than ``speed_tol`` [m/s]
    leave the cone of half-width ``theta_b`` [rad] about the world directions ``middle(moving)`` [rad]
    (one per moving sample, ``moving`` the (K,) mask of those samples); 0 where none moves."""
    moving = np.linalg.norm(v, axis=1) > speed_tol
    if not np.any(moving):
        return 0.0
    ang = np.arctan2(v[moving, 1], v[moving, 0]) - middle(moving)
    return float(max(0.0, (np.abs(wrap_angle(ang)) - theta_b).max()))


def realised_offsets(base: NDArray[np.float64], x: NDArray[np.float64],
                     yaw: NDArray[np.float64]) -> NDArray[np.float64]:
    """The object's offsets [m] (K,) from the arm's plane with the object at ``x`` (K, 2) [m] and the
    tool at yaw ``yaw`` (K,) [rad] (a realised push's poses), the joint-1 axis at ``base`` (2,) [m]:
    ``p_o = b + R(a) (u, offset)`` with ``a = yaw + pi/2`` (:mod:`~.face_frame`), so ``offset`` is
    ``p_o - b`` along ``(-sin a, cos a) = -(cos yaw, sin yaw)``."""
    if len(yaw) != len(x):
        raise InputError("realised_offsets", "x and yaw of one length", f"{len(x)}, {len(yaw)}")
    d = np.asarray(x, dtype=np.float64) - base
    return -(d[:, 0] * np.cos(yaw) + d[:, 1] * np.sin(yaw))


def _chords(frame: FaceFrame, tol: float,
            near: tuple[float, float] | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Half-planes of chords inside the outer arc (radius ``hypot(u_out, offset)``) within ``tol``;
    with ``near`` (polar angles [rad] about the base), only the chords within 0.5 rad of that range."""
    u_out = frame.reach[1]
    r_out = float(np.hypot(u_out, frame.offset))
    g = float(np.arctan2(frame.offset, u_out))
    lo, hi = frame.waist[0] + min(g, 0.0), frame.waist[1] + max(g, 0.0)
    half = float(np.arccos(r_out / (r_out + tol)))
    n = max(1, int(np.ceil((hi - lo) / (2.0 * half))))
    mids = lo + (np.arange(n) + 0.5) * (hi - lo) / n
    if near is not None:
        keep = (mids >= near[0] - 0.5) & (mids <= near[1] + 0.5)
        mids = mids[keep] if keep.any() else mids
    g_rows = np.stack([np.cos(mids), np.sin(mids)], axis=1)
    return g_rows, r_out * np.cos(0.5 * (hi - lo) / n) + g_rows @ frame.base


def reach_constraints(
    frame: FaceFrame, *, window: tuple[float, float] | None = None, tol: float = 2e-4, family: str = "reach",
    near: tuple[float, float] | None = None,
) -> list[Constraint]:
    """Constraints keeping the object where ``frame``'s face can push it from (inner approximation
    within ``tol`` [m] of the exact sector on the outer arc). ``near``: the polar angles [rad] about
    the base the path is expected to span in the window; the outer arc's chords farther than 0.5 rad
    from them are left out (they cannot be reached from there within a fit; the plan's exact
    joint-limit check stands behind)."""
    rows_g, rows_h = [], []
    for a, sign in ((frame.waist[0], -1.0), (frame.waist[1], 1.0)):
        n = np.array([-np.sin(a), np.cos(a)])  # direction of increasing waist angle at that side
        rows_g.append(sign * n)
        rows_h.append(sign * (frame.offset + n @ frame.base))
    cg, ch = _chords(frame, tol, near)
    polygon = PositionPolygon(np.vstack([np.array(rows_g), cg]), np.concatenate([rows_h, ch]), family=family,
                              window=window)
    r_in = float(np.hypot(frame.reach[0], frame.offset))
    return [polygon, OutsideDisc(frame.base, r_in, family=family, window=window)]


def reach_entry(rows: list[Constraint], points: NDArray[np.float64], tol: float = 1e-6) -> int:
    """Index of the first of ``points`` (K, 2) [m] that satisfies every row of
    :func:`reach_constraints` (``rows``) within ``tol`` [m]; ``K`` when none does."""
    ok = np.ones(len(points), dtype=bool)
    for c in rows:
        if isinstance(c, PositionPolygon):
            ok &= np.all(points @ c.A.T - c.b <= tol, axis=1)
        elif isinstance(c, OutsideDisc):
            ok &= np.hypot(*(points - c.center).T) >= c.radius - tol
    return int(np.argmax(ok)) if ok.any() else len(points)


def heading_gradient(frame: FaceFrame, p: NDArray[np.float64]) -> NDArray[np.float64]:
    """Gradient (K, 2) [rad/m] of the tool heading :meth:`FaceFrame.heading` with the object at
    ``p`` (K, 2) [m]: ``((-d_y, d_x) + offset d / u) / |d|^2`` with ``d = p - base``."""
    d = p - frame.base
    r2 = np.einsum("ij,ij->i", d, d)
    u = np.sqrt(np.maximum(r2 - frame.offset**2, 1e-18))
    return (np.stack([-d[:, 1], d[:, 0]], axis=1) + frame.offset * d / u[:, None]) / r2[:, None]


class ContactOnFace(Constraint):
    """The contact stays on the face's usable segment (``[lo, hi]``, arc length [m]) over the window.

    While the contact sticks it rolls along the face at ``ds/dt = a(x) . v`` with
    ``a(x) = -(1/c^2) e_w(x) - sigma R grad psi(x)`` (:mod:`tooltransfer.tools.pushing.inverse`: the object's
    sideways travel in the face frame and the heading's turn, ``e_w`` the face's world direction at
    the heading ``psi`` the Omni imposes with the object at ``x``). A push may use up to
    ``max_contacts`` contacts (re-contacts in between, placed by :mod:`tooltransfer.planner.planning.oe.contacts`), so
    the contact's total travel ``int |ds|`` must stay within that many usable lengths. The rows bound the
    rolling *rate* sample by sample,

        |a(x_k) . v_k| <= g_k,

    with the budget ``g`` shared out along the push as the first linearisation path rolls (that
    path, the fit without these rows, is the reference), scaled so that ``int g dt`` is
    ``max_contacts`` usable lengths: a path that needs fewer contacts meets the rows as it is (then
    the fit need not run with them at all: :meth:`need`), one that needs more is bent where it rolls
    most. Velocity rows linearised at the current path like the cone's (``a`` from it): exact on that
    path, non-conservative.
    """

    linearised = True
    conservative = False

    def __init__(self, frame: FaceFrame, face: FaceGeometry, mech: PushMechanics, radius: float,
                 lo: float, hi: float, *, max_contacts: int = 1, family: str = "contact",
                 window: tuple[float, float] | None = None) -> None:
        super().__init__(family, window)
        if not hi > lo:
            raise InputError("contact range", f"hi > lo [m] on face {face.name!r}", f"[{lo}, {hi}]")
        self.frame, self.face, self.mech, self.radius, self.lo, self.hi = frame, face, mech, radius, lo, hi
        self.max_contacts = max_contacts
        self._budget: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    def rolling_rate(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """``a(x)`` (K, 2): the contact's speed along the face per object velocity, object at ``x`` (K, 2) [m]."""
        psi = self.frame.heading(x)
        e = self.face.direction
        c, s = np.cos(psi), np.sin(psi)
        e_w = np.stack([c * e[0] - s * e[1], s * e[0] + c * e[1]], axis=1)
        return -self.mech.rolling * e_w - self.face.sigma * self.radius * heading_gradient(self.frame, x)

    def need(self, t: NDArray[np.float64], x: NDArray[np.float64], v: NDArray[np.float64]) -> float:
        """The contact's total travel ``int |ds|`` [m] over the window along the path ``x``, ``v``
        (T, 2) at times ``t`` (T,) [s]: one contact carries the push when it is at most ``hi - lo``."""
        k = self.samples(t)
        if k.size < 2:
            return 0.0
        rate = np.abs(np.einsum("ij,ij->i", self.rolling_rate(x[k]), v[k]))
        return float(np.sum(0.5 * (rate[:-1] + rate[1:]) * np.diff(t[k])))

    def _coefficients(self, k: NDArray[np.intp], t: NDArray[np.float64], x_lin: NDArray[np.float64]) -> Coefficients:
        if x_lin.shape[1] != 2:
            raise InputError("ContactOnFace", "a planar (2-D) motion", f"{x_lin.shape[1]}-D")
        if k.size < 3:
            return Coefficients(k[:0], None, np.zeros((0, 2, 2)), np.zeros((0, 2)))
        x = x_lin[k]
        a = self.rolling_rate(x)
        if self._budget is None:  # the first linearisation (the fit without these rows) shares out the budget
            v = np.gradient(x, t[k], axis=0)
            rate = np.abs(np.einsum("ij,ij->i", a, v))
            total = float(np.sum(0.5 * (rate[:-1] + rate[1:]) * np.diff(t[k])))
            span = float(t[k][-1] - t[k][0])
            allowed = self.max_contacts * (self.hi - self.lo)
            # 90 % where the reference rolls, 10 % spread evenly (room to roll where it did not)
            share = 0.9 * rate / total + 0.1 / span if total > 0 else np.full(k.size, 1.0 / span)
            self._budget = (t[k].copy(), allowed * share)
        tb, g = self._budget
        bound = np.interp(t[k], tb, g)
        rows = np.stack([a, -a], axis=1)
        return Coefficients(k, None, rows, np.stack([bound, bound], axis=1))
