"""The only plant the closed loop holds: every call checked, every command inside the envelope.

:class:`GuardedPlant` wraps any :class:`tooltransfer.planner.execution.plant.Plant`. The closed loop
builds it around the plant it is given and keeps no other reference, so no code path of the loop
(first approach, pushes, switches, re-contacts, re-plans, corrections, staged pushes, retreats) can
command the tool without :meth:`GuardedPlant.move_tool`, which refuses (raises
:class:`~tooltransfer.planner.execution.loop_stop.UnsafeCommand`, sending nothing) a command the
:class:`~tooltransfer.planner.execution.envelope.SafetyEnvelope` finds a violation in.

It also turns what the plant does wrong into the loop's faults, each naming the method and the value:
an exception raised by a plant method becomes a
:class:`~tooltransfer.planner.execution.loop_stop.PlantCallError`; a value of the wrong shape, type or
not finite a :class:`BadValue`. The loop decides what a fault means (a dropped camera frame is
retried: :mod:`tooltransfer.planner.execution.health`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from tooltransfer.planner.execution.envelope import SafetyEnvelope
from tooltransfer.planner.execution.loop_stop import PlantCallError, SensorFault, UnsafeCommand
from tooltransfer.planner.execution.plant import Plant

#: Readings of the tool pose taken before an unusable one ends the run.
POSE_TRIES = 3
#: Duration [s] of the hold command that stops the tool where it is.
HOLD = 0.05


class BadValue(SensorFault):
    """A plant method returned a value of the wrong shape, type or a non-finite one."""

    def __init__(self, method: str, value: object, expected: str) -> None:
        self.method, self.value = method, value
        try:
            text = " ".join(repr(value).split())
        except Exception:  # a value whose repr fails is named by its type
            text = f"a {type(value).__name__}"
        super().__init__(f"plant.{method} returned {text[:120]} (expected {expected})")


def _vector(method: str, value: object, n: int) -> NDArray[np.float64]:
    expected = f"{n} finite numbers"
    try:
        v = np.array(value, dtype=np.float64)
    except Exception as exc:  # not array-like at all
        raise BadValue(method, value, expected) from exc
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise BadValue(method, value, expected)
    return v


class GuardedPlant:
    """``plant`` behind the checks of the module docstring; ``envelope``: where the tool may go.

    Attributes:
        envelope: the safety envelope.
        sent: the commands sent (``(t, tool_pose)``, as sent).
        refused: the reasons of the commands refused.
        bias: the arm's known tracking offset (2,) [m] (the tool goes ``bias`` off its command): a
            command is checked from the reported pose less ``bias`` and, with a bias, also as the
            tool tracks it.
    """

    def __init__(self, plant: Plant, envelope: SafetyEnvelope) -> None:
        self._plant = plant
        self.envelope = envelope
        self.sent: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
        self.refused: list[str] = []
        self.bias = np.zeros(2)

    def _call(self, method: str, *args: Any) -> Any:
        fn: Callable[..., Any] = getattr(self._plant, method)
        try:
            return fn(*args)
        except (Exception, SystemExit) as exc:  # a driver's sys.exit() ends the run, not the program
            raise PlantCallError(method, exc) from exc

    def observe_object(self) -> NDArray[np.float64]:
        """One camera frame (2,) [m]; :class:`BadValue` for an unusable one."""
        return _vector("observe_object", self._call("observe_object"), 2)

    def tool_pose(self) -> NDArray[np.float64]:
        """The reported tool pose (3,); up to :data:`POSE_TRIES` readings (one that raises or is
        unusable is taken again) until one is usable, else the last one's fault."""
        for attempt in range(POSE_TRIES):
            try:
                return _vector("tool_pose", self._call("tool_pose"), 3)
            except (BadValue, PlantCallError):
                if attempt == POSE_TRIES - 1:
                    raise
        raise AssertionError("unreachable")  # pragma: no cover

    def move_tool(self, t: NDArray[np.float64], tool_pose: NDArray[np.float64]) -> None:
        """Send the command when the envelope holds along it from the reported pose, else raise
        :class:`UnsafeCommand` without sending it."""
        tt, pose = np.asarray(t, dtype=np.float64), np.asarray(tool_pose, dtype=np.float64)
        why = None
        if tt.ndim != 1 or tt.size < 2 or pose.shape != (tt.size, 3) or not np.all(np.isfinite(tt)) \
                or tt[0] != 0.0 or np.any(np.diff(tt) <= 0):
            why = f"a command of {tt.shape} times and {pose.shape} poses (expected K >= 2 increasing times from 0)"
        else:
            here = self.tool_pose()
            bias = np.append(self.bias, 0.0)
            why = self.envelope.violation(here - bias, pose)
            if why is None and np.any(bias):
                tracked = self.envelope.violation(here, pose + bias)
                why = None if tracked is None else f"{tracked} (where the tool tracks the command)"
        if why is not None:
            self.refused.append(why)
            raise UnsafeCommand(f"refused a tool command: {why}")
        self._call("move_tool", tt, pose)
        self.sent.append((tt, pose))

    def true_object(self) -> NDArray[np.float64] | None:
        """The plant's true object centre (2,) [m] when it tells it (a simulator), else None."""
        if not callable(getattr(self._plant, "true_object", None)):
            return None
        return _vector("true_object", self._call("true_object"), 2)

    @property
    def execution(self) -> object:
        """The plant's recording when it keeps one (the MuJoCo platform), else None."""
        try:
            return getattr(self._plant, "execution", None)
        except Exception:
            return None

    def hold(self) -> None:
        """Stop the tool: the plant's own ``stop()`` when it has one, else a command to stay at the
        reported pose (through the envelope). Never raises but ``KeyboardInterrupt``."""
        try:
            if callable(getattr(self._plant, "stop", None)):
                self._call("stop")
                return
            here = self.tool_pose() - np.append(self.bias, 0.0)
            self.move_tool(np.array([0.0, HOLD]), np.vstack([here, here]))
        except Exception:  # stopping is best effort: the run is ending anyway
            pass
