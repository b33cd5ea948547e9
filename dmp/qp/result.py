"""Result of a constrained DMP fit, in domain words."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from tooltransfer.dmp.trajectory import Rollout
from tooltransfer.errors import InfeasibleError


@dataclass
class FitResult:
    """Outcome of :func:`tooltransfer.dmp.qp.solve.solve_fit`.

    Attributes:
        status: ``"solved"`` (every constraint holds on the dense grid within ``tol``),
            ``"inaccurate"`` (a solution whose measured violation exceeds ``tol``), or
            ``"infeasible"``.
        weights: (N, n), None when infeasible.
        violations: true maximum violation per constraint family on the dense grid [m or m/s].
        objective: value of ``0.5 w'Pw + q'w``.
        rollout: the motion on the dense grid.
        build_time, solve_time: [s]; iterations: backend iterations summed (None if unknown);
        n_qp: backend calls; n_exact: add/drop steps of the exact dual active-set method, over
        all linearisations (the rows a warm start takes at once are not counted); n_rows:
        inequality rows active at the end (cutting planes) or in the QP (full); scp_iterations:
        outer linearisation rounds; families/reason: for infeasible problems.
    """

    status: Literal["solved", "inaccurate", "infeasible"]
    solver: str
    strategy: str
    weights: NDArray[np.float64] | None = None
    violations: dict[str, float] = field(default_factory=dict)
    objective: float = float("nan")
    rollout: Rollout | None = None
    build_time: float = 0.0
    solve_time: float = 0.0
    iterations: int | None = 0
    n_qp: int = 0
    n_rows: int = 0
    scp_iterations: int = 0
    exact_finish: bool = False
    n_exact: int = 0
    families: tuple[str, ...] = ()
    reason: str = ""

    @property
    def max_violation(self) -> float:
        """Largest true violation over all families [m or m/s]."""
        return max(self.violations.values(), default=0.0)

    @property
    def ok(self) -> bool:
        return self.status == "solved"

    def raise_if_infeasible(self, problem: str = "constrained DMP fit") -> FitResult:
        """Raise :class:`InfeasibleError` naming the families if infeasible; else return self."""
        if self.status == "infeasible":
            raise InfeasibleError(problem, self.families, self.reason)
        return self
