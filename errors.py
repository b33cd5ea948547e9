"""Exception hierarchy shared by every package of tooltransfer.

One root, :class:`ToolTransferError`, so a caller can catch everything the library raises on
purpose; specific errors below it carry the data a caller needs (the field, the constraint
families), and a backend's own exceptions are wrapped, never shown raw.
"""

from __future__ import annotations

from collections.abc import Iterable


class ToolTransferError(Exception):
    """Root of every error tooltransfer raises on purpose."""


class InputError(ToolTransferError, ValueError):
    """A value given to a public function is invalid.

    Attributes:
        field: Name of the offending argument or field path (e.g. ``"X[1]"``).
        expected: What was expected, in words.
    """

    def __init__(self, field: str, expected: str, got: object | None = None) -> None:
        self.field = field
        self.expected = expected
        self.got = got
        msg = f"{field}: expected {expected}"
        if got is not None:
            msg += f", got {got}"
        super().__init__(msg)


class SkillFileError(ToolTransferError):
    """A saved skill file is missing, corrupted or of an unsupported format version."""

    def __init__(self, path: str, reason: str) -> None:
        self.path = path
        self.reason = reason
        super().__init__(f"{path}: {reason}")


class InfeasibleError(ToolTransferError):
    """An optimization problem has no solution.

    Attributes:
        problem: Short name of the problem (e.g. ``"constrained DMP fit"``).
        families: Names of the constraint families involved in the infeasibility.
        reason: Human-readable explanation.
    """

    def __init__(self, problem: str, families: Iterable[str], reason: str) -> None:
        self.problem = problem
        self.families = tuple(families)
        self.reason = reason
        fam = ", ".join(self.families) if self.families else "unknown"
        super().__init__(f"{problem} is infeasible (constraint families: {fam}): {reason}")


class SolverError(ToolTransferError):
    """A numerical backend failed for a reason other than infeasibility."""

    def __init__(self, solver: str, reason: str) -> None:
        self.solver = solver
        self.reason = reason
        super().__init__(f"solver {solver!r} failed: {reason}")


class UnknownSolverError(ToolTransferError, ValueError):
    """A QP backend name is not known or not installed; lists what is available."""

    def __init__(self, name: str, available: Iterable[str]) -> None:
        self.name = name
        self.available = tuple(available)
        super().__init__(
            f"unknown or uninstalled QP solver {name!r}; installed: {', '.join(self.available)}. "
            "Install others with `pip install qpsolvers[open_source_solvers]` "
            "or the tooltransfer[bench] extra."
        )
