"""The quasi-static contact law of a pusher on a round slider (docs/design.md section 10).

The puck (radius ``R``) slides on the table; with an ellipsoidal limit surface
``f^2 / f_max^2 + m^2 / m_max^2 = 1`` its twist lies along the surface's normal, ``v = k f / f_max^2``
and ``omega = k m / m_max^2``, and ``c = m_max / (R f_max)`` (2/3 for uniform support pressure, 1
for support on the rim). A pusher touching the rim at ``q = centre - R n`` with the contact normal
``n`` (unit, pointing from the pusher into the puck, through its centre) applies ``f = f_n n + f_t t``
(``t = J n``, ``J`` the quarter turn counter-clockwise) and the moment ``m = -R f_t`` about the
centre, so

    v_centre        = (k / f_max^2) (f_n n + f_t t)
    v_rim point q   = v_centre - omega R t = (k / f_max^2) (f_n n + kappa f_t t),   kappa = 1 + 1/c^2.

The centre moves *along the contact force*; the puck's material point at the contact moves
``kappa`` times faster sideways. With Coulomb friction ``|f_t| <= mu f_n`` at the contact, a pusher
point moving by ``d = a n + b t`` (``a > 0`` into the puck) gives

* **sticking** while ``|b| <= mu kappa a``: the rim point moves with the pusher, the centre by
  ``a n + (b / kappa) t``, i.e. ``tan(phi_c) = tan(phi_p) / kappa``;
* **sliding** beyond: the force lies on the friction cone's edge, the centre moves by
  ``a (n + sign(b) mu t)`` (``|phi_c| = atan(mu)``) and the pusher slips along the rim;
* **separation** when ``a <= 0``: no force, the puck stays (quasi-static: no inertia).

So the centre's direction always lies in the friction cone ``|phi_c| <= atan(mu)`` about ``n``.
The table's friction only scales the forces; it does not enter the motion. Everything here is
per contact and vectorised over a leading batch axis.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tooltransfer.errors import InputError

#: Contact modes of :func:`object_displacement` (``mode`` arrays hold these codes).
FREE, STICK, SLIDE = 0, 1, 2
MODE_NAMES: dict[int, str] = {FREE: "free", STICK: "stick", SLIDE: "slide"}

Source = Literal["default", "identified", "task", "given"]


@dataclass(frozen=True)
class PushMechanics:
    """Parameters of the quasi-static push model.

    Attributes:
        mu: Coulomb friction coefficient between the tool and the puck (dimensionless, > 0).
        c: limit-surface ratio ``m_max / (R f_max)`` of the puck on the table (dimensionless, in
            (0, 2]): 2/3 for uniform pressure, 1 for a rim, the MuJoCo platform behaves like 0.59.
        source: where the values come from (``"identified"`` from recordings, ``"task"`` a task
            file's override, ``"default"`` the platform's nominal values, ``"given"`` by a caller).
        mu_std, c_std: one-sigma uncertainty of an identification (0 when not identified).
    """

    mu: float = 0.8
    c: float = 0.59
    source: Source = "given"
    mu_std: float = 0.0
    c_std: float = 0.0

    def __post_init__(self) -> None:
        for name, hi in (("mu", 10.0), ("c", 2.0)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | float | np.floating) or not np.isfinite(v) \
                    or not 0.0 < v <= hi:
                raise InputError(f"mechanics.{name}", f"a number in (0, {hi}]", repr(v))
            object.__setattr__(self, name, float(v))
        for name in ("mu_std", "c_std"):
            v = float(getattr(self, name))
            if not np.isfinite(v) or v < 0:
                raise InputError(f"mechanics.{name}", "a finite number >= 0", repr(v))
            object.__setattr__(self, name, v)

    @property
    def kappa(self) -> float:
        """``1 + 1/c^2``: sideways speed of the rim point at the contact per sideways speed of the centre."""
        return 1.0 + 1.0 / self.c**2

    @property
    def friction_angle(self) -> float:
        """Half-angle [rad] of the friction cone, ``atan(mu)``: the largest angle of the centre's
        motion off the contact normal."""
        return float(np.arctan(self.mu))

    @property
    def rolling(self) -> float:
        """``1/c^2 = kappa - 1``: how far the contact slides along a sticking face per unit of the
        centre's sideways travel (in the face's frame, opposite sense)."""
        return 1.0 / self.c**2

    def with_values(self, mu: float, c: float, source: Source = "given") -> PushMechanics:
        """A copy with other ``mu`` and ``c`` (no uncertainty)."""
        return PushMechanics(mu, c, source)

    def to_dict(self) -> dict[str, float | str]:
        """JSON-ready fields."""
        return {"mu": self.mu, "c": self.c, "source": self.source, "mu_std": self.mu_std, "c_std": self.c_std}

    @classmethod
    def from_dict(cls, data: dict, field: str = "mechanics") -> PushMechanics:
        """From :meth:`to_dict` output (``mu`` and ``c`` required)."""
        if not isinstance(data, dict) or "mu" not in data or "c" not in data:
            raise InputError(field, "a mapping with 'mu' and 'c'", type(data).__name__)
        source = data.get("source", "given")
        if source not in ("default", "identified", "task", "given"):
            raise InputError(f"{field}.source", "default, identified, task or given", repr(source))
        return cls(data["mu"], data["c"], source, data.get("mu_std", 0.0), data.get("c_std", 0.0))


#: The MuJoCo platform's nominal values (tool-puck friction 0.8; c measured on straight pushes).
PLATFORM_MECHANICS = PushMechanics(0.8, 0.59, "default")


def perp(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Quarter turn counter-clockwise of vectors (..., 2): ``J v = (-v_y, v_x)``."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def object_displacement(
    approach: ArrayLike, slip: ArrayLike, normal: ArrayLike, mech: PushMechanics
) -> tuple[NDArray[np.float64], NDArray[np.int8]]:
    """The centre's displacement for a pusher point's displacement ``approach n + slip t``.

    Args:
        approach: (B,) how far [m] the pusher moves into the puck along ``normal`` (<= 0: no push).
        slip: (B,) the pusher point's displacement [m] along ``t = J n``.
        normal: (B, 2) unit contact normals, pusher to puck centre.
        mech: the model's parameters.
    Returns:
        The centre's displacement (B, 2) [m] and the mode (B,) (:data:`FREE`, :data:`STICK`, :data:`SLIDE`).
    """
    a = np.asarray(approach, dtype=np.float64)
    b = np.asarray(slip, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    pushing = a > 0.0
    stick = pushing & (np.abs(b) <= mech.mu * mech.kappa * a)
    lateral = np.where(stick, b / mech.kappa, np.sign(b) * mech.mu * np.maximum(a, 0.0))
    lateral = np.where(pushing, lateral, 0.0)
    d = np.maximum(a, 0.0)[..., None] * n + lateral[..., None] * perp(n)
    mode = np.where(stick, STICK, np.where(pushing, SLIDE, FREE)).astype(np.int8)
    return d, mode


def pusher_velocity(v_object: ArrayLike, normal: ArrayLike, mech: PushMechanics) -> NDArray[np.float64]:
    """The inverse for sticking: the pusher point's velocity (B, 2) that moves the centre with
    ``v_object`` (B, 2) [m/s] through a contact with unit normals ``normal`` (B, 2): the same normal
    component, ``kappa`` times the sideways one. Valid while ``|v_t| <= mu v_n`` (in the friction cone)."""
    v = np.asarray(v_object, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    t = perp(n)
    vn = np.einsum("...i,...i->...", v, n)
    vt = np.einsum("...i,...i->...", v, t)
    return vn[..., None] * n + (mech.kappa * vt)[..., None] * t


def cone_margin(v_object: ArrayLike, normal: ArrayLike, mech: PushMechanics) -> NDArray[np.float64]:
    """``atan(mu) - |phi_c|`` [rad] (B,): how far inside the friction cone the centre's motion
    ``v_object`` (B, 2) lies about ``normal`` (B, 2) (negative outside; ``-pi`` for a pull)."""
    v = np.asarray(v_object, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    vn = np.einsum("...i,...i->...", v, n)
    vt = np.einsum("...i,...i->...", v, perp(n))
    phi = np.arctan2(np.abs(vt), vn)
    return np.where(vn > 0, mech.friction_angle - phi, -np.pi)
