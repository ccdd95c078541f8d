"""The error events the SynScan parsers hand out (each names the byte and the reason)."""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.protocol.base import Event
from scopelink.protocol.synscan.message import Command


@dataclass(frozen=True, slots=True)
class UnknownCommand(Event):
    """A byte that starts no SynScan command; it was skipped."""

    byte: int
    offset: int
    """Stream offset of the byte."""

    def describe(self) -> str:
        """What went wrong, in words."""
        return f"unknown command byte 0x{self.byte:02X} at offset {self.offset}, skipped"


@dataclass(frozen=True, slots=True)
class MalformedCommand(Event):
    """A command frame whose payload does not parse; the whole frame was discarded."""

    frame: bytes
    index: int
    """Index of the offending byte within ``frame``."""
    offset: int
    """Stream offset of the frame's first byte."""
    reason: str

    @property
    def error_offset(self) -> int:
        """Stream offset of the offending byte."""
        return self.offset + self.index

    def describe(self) -> str:
        """What went wrong, in words."""
        return (
            f"malformed {chr(self.frame[0])!r} command {self.frame!r}: {self.reason} "
            f"(byte {self.index}, offset {self.error_offset}); frame discarded"
        )


@dataclass(frozen=True, slots=True)
class MalformedReply(Event):
    """A reply that does not fit the shape its command expects; the bytes read so far are in
    ``data``.

    The connection refuses new commands until ``reset()``.
    """

    command: Command
    data: bytes
    index: int
    """Index of the offending byte within ``data`` (its last byte)."""
    reason: str

    def describe(self) -> str:
        """What went wrong, in words."""
        return (
            f"reply to {self.command.describe()!r} does not fit: {self.reason} "
            f"(byte {self.index} of {self.data!r})"
        )


@dataclass(frozen=True, slots=True)
class UnexpectedData(Event):
    """Bytes that arrived when no reply was expected, or that were skipped while resynchronising."""

    data: bytes

    def describe(self) -> str:
        """What went wrong, in words."""
        return f"{len(self.data)} unexpected bytes {self.data!r} discarded"


ServerError = UnknownCommand | MalformedCommand
"""Error events of the command (server) side."""

ClientError = MalformedReply | UnexpectedData
"""Error events of the reply (client) side."""
