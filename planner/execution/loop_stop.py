"""Why a closed-loop run ends early: :class:`LoopStop` and the faults below it.

Every way the closed loop (:func:`tooltransfer.planner.execution.closed_loop.execute_closed_loop`) stops
before reaching the target is one of these exceptions, caught by the loop and turned into the report's
``status`` and ``reason``; ``retreat`` says whether the tool backs off the object first (a fault of the
sensors or the arm, where the tool may still touch the object).

Statuses: ``"failed"`` (a move refused by the planners, or a plant method that raised),
``"unsafe"`` (a command the safety envelope refused: :mod:`tooltransfer.planner.execution.envelope`),
``"sensor_fault"`` (the camera or the encoders: frozen frames, too many dropped or unusable values,
an object seen where the tool is), ``"tracking_fault"`` (the tool does not follow its command) and
``"disturbed"`` (the object displaced by something else, into an obstacle's margin).
"""

from __future__ import annotations

from tooltransfer.errors import ToolTransferError


class LoopStop(ToolTransferError):
    """The run ends with ``status`` and ``reason`` (module docstring); ``retreat``: the tool backs off
    the object first."""

    status = "failed"
    retreat = False

    def __init__(self, reason: str, status: str | None = None) -> None:
        self.reason = reason
        if status is not None:
            self.status = status
        super().__init__(reason)


class PlantCallError(LoopStop):
    """A plant method raised: ``method`` and the exception in the reason."""

    def __init__(self, method: str, exc: BaseException) -> None:
        self.method = method
        super().__init__(f"plant.{method} raised {type(exc).__name__}: {exc}")


class UnsafeCommand(LoopStop):
    """A tool command the safety envelope refused (it was not sent)."""

    status = "unsafe"


class NoToolPath(LoopStop):
    """No switch or re-contact has a tool path from the contact the tool just left to the next push's
    contact pose, the object where it is observed (nothing was commanded toward it). The loop corrects
    from there instead, as after a refused command; the run ends ``failed`` only when that fails too."""


class SensorFault(LoopStop):
    """The camera or the encoders give values the loop cannot trust."""

    status = "sensor_fault"
    retreat = True


class TrackingFault(LoopStop):
    """The reported tool pose is off the commanded one beyond the bound."""

    status = "tracking_fault"
    retreat = True


class Disturbed(LoopStop):
    """The object was displaced by something else than the tool, to where the loop must not go on."""

    status = "disturbed"
    retreat = True
