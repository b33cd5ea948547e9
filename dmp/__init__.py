"""DMP core of tooltransfer: discrete DMPs with exact affine rollout and constrained fitting.

Notation used throughout (paper eqs. 1-5, docs/design.md section 3): positions ``x`` [m], velocities
``v = dx/dt`` [m/s], goal ``g``, start ``x0``, duration ``tau`` [s], phase ``s``, ``N`` basis
functions ``psi_i(s)`` per dimension, weights ``W`` of shape (N, n), flattened row-major into ``w``.
"""

from tooltransfer.dmp.affine import AffineRollout
from tooltransfer.dmp.online import DMPState
from tooltransfer.dmp.primitive import DMP
from tooltransfer.dmp.trajectory import Rollout
from tooltransfer.errors import (
    InfeasibleError,
    InputError,
    SkillFileError,
    SolverError,
    ToolTransferError,
    UnknownSolverError,
)

__all__ = [
    "DMP",
    "AffineRollout",
    "DMPState",
    "InfeasibleError",
    "InputError",
    "Rollout",
    "SkillFileError",
    "SolverError",
    "ToolTransferError",
    "UnknownSolverError",
]
