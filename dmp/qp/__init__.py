"""Constrained DMP fitting as a QP (docs/design.md section 4): build with :func:`build_fit_qp`, solve with
:func:`solve_fit`; constraints in :mod:`tooltransfer.dmp.qp.constraints`, objectives in
:mod:`tooltransfer.dmp.qp.objectives`."""

import os

# OSQP picks its linear-algebra backend for every solver it creates by trying to import each
# optional one (CUDA, MKL) before the built-in, a large part of the constrained fit's seed QP when
# they are absent. OSQP's documented switch fixes the choice; it is read
# when osqp is first imported (so here, before qpsolvers), and a user's own setting wins.
os.environ.setdefault("OSQP_ALGEBRA_BACKEND", "builtin")

from tooltransfer.dmp.qp.constraints import (
    Constraint,
    FixedEndPoint,
    OutsideDisc,
    OutsidePolygon,
    PositionPolygon,
    Rows,
    VelocityCone,
    ZeroEndVelocity,
)
from tooltransfer.dmp.qp.objectives import MatchForcing, Objective, Ridge, TrackPath
from tooltransfer.dmp.qp.problem import FitProblem, FitQP, build_fit_qp
from tooltransfer.dmp.qp.result import FitResult
from tooltransfer.dmp.qp.solve import solve_fit

__all__ = [
    "Constraint",
    "FitProblem",
    "FitQP",
    "FitResult",
    "FixedEndPoint",
    "MatchForcing",
    "Objective",
    "OutsideDisc",
    "OutsidePolygon",
    "PositionPolygon",
    "Ridge",
    "Rows",
    "TrackPath",
    "VelocityCone",
    "ZeroEndVelocity",
    "build_fit_qp",
    "solve_fit",
]
