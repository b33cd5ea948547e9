"""Errors of the tool library and the Omni model, below :class:`tooltransfer.errors.ToolTransferError`."""

from __future__ import annotations

from collections.abc import Iterable

from tooltransfer.errors import ToolTransferError


class ToolSpecError(ToolTransferError, ValueError):
    """A tool description (YAML file or constructor arguments) is invalid.

    Attributes:
        tool: Name of the tool (or the file path when the name is unknown).
        field: Path of the offending field, e.g. ``"faces[1].theta_b"``.
        reason: What is wrong, in words.
    """

    def __init__(self, tool: str, field: str, reason: str) -> None:
        self.tool = tool
        self.field = field
        self.reason = reason
        super().__init__(f"tool {tool!r}, field {field}: {reason}")


class UnknownToolError(ToolTransferError, KeyError):
    """A tool name is not in the library; lists the valid names."""

    def __init__(self, name: str, valid: Iterable[str]) -> None:
        self.name = name
        self.valid = tuple(sorted(valid))
        super().__init__(name)
        self._msg = f"unknown tool {name!r}; library tools: {', '.join(self.valid)}"

    def __str__(self) -> str:
        return self._msg


class UnknownFaceError(ToolTransferError, KeyError):
    """A face name is not a face of the tool; lists the tool's faces."""

    def __init__(self, tool: str, name: str, valid: Iterable[str]) -> None:
        self.tool = tool
        self.name = name
        self.valid = tuple(valid)
        super().__init__(name)
        self._msg = f"tool {tool!r} has no face {name!r}; faces: {', '.join(self.valid)}"

    def __str__(self) -> str:
        return self._msg
