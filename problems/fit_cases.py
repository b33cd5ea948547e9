"""Named constrained-fit problems shared by the tests, the benchmark and the demo.

``l_push_case`` is the problem class ``benchmarks/bench_dmp.py`` measures: an L-shaped pushing path (a
forward push, a corner, a leftward push) fitted with 2 x N weights, under a velocity cone around
the mean push direction, a 6-sided workspace polygon that clips the corner, and a disc obstacle on the
first leg, passed on the left, linearised: 9 rows per sample, every family active.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp import DMP
from tooltransfer.dmp.qp import (
    FitProblem,
    FixedEndPoint,
    OutsideDisc,
    PositionPolygon,
    TrackPath,
    VelocityCone,
    ZeroEndVelocity,
)


def minimum_jerk(p0: NDArray[np.float64], p1: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Minimum-jerk segment from ``p0`` to ``p1`` with ``n`` samples, shape (n, d) [m]."""
    p0, p1 = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
    s = np.linspace(0.0, 1.0, n)[:, None]
    b = 10 * s**3 - 15 * s**4 + 6 * s**5
    return p0 + (p1 - p0) * b


def l_path(n_samples: int, duration: float = 4.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """L-shaped push: 100 mm forward (+y), then 80 mm leftward (-x). Times (T,) [s], path (T, 2) [m]."""
    t = np.linspace(0.0, duration, n_samples)
    n1 = n_samples // 2
    a, b, c = np.array([0.0, 0.0]), np.array([0.0, 0.10]), np.array([-0.08, 0.10])
    path = np.vstack([minimum_jerk(a, b, n1), minimum_jerk(b, c, n_samples - n1 + 1)[1:]])
    return t, path


HEXAGON = np.array([[0.02, -0.02], [0.02, 0.06], [-0.02, 0.115], [-0.10, 0.115], [-0.10, -0.02], [-0.04, -0.04]])
"""Workspace polygon [m]: its diagonal side cuts the L's corner (at x = 0 it allows y <= 87.5 mm)."""


@dataclass(frozen=True)
class Case:
    """A fit problem with the reference path that defines it."""

    problem: FitProblem
    t: NDArray[np.float64]
    reference: NDArray[np.float64]


def l_push_case(n_basis: int = 30, n_samples: int = 200, theta_b: float = 0.78, obstacle: bool = True) -> Case:
    """The L-push constrained fit (see module docstring) with ``n_basis`` weights per dimension."""
    t, ref = l_path(n_samples)
    dmp = DMP(2, n_basis=n_basis).fit(t, ref)
    cons = [
        VelocityCone(3 * np.pi / 4, theta_b),
        PositionPolygon.from_vertices(HEXAGON),
        FixedEndPoint(ref[-1]),
        ZeroEndVelocity(),
    ]
    if obstacle:
        cons.append(OutsideDisc([0.006, 0.045], 0.012, side="left"))
    prob = FitProblem(dmp, t, x0=ref[0], g=ref[-1], objectives=[TrackPath(ref)], constraints=cons)
    return Case(prob, t, ref)
