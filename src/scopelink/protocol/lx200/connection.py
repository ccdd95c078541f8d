"""Framing of the LX200 command stream on the handset's side.

Commands run from ``:`` to ``#``; the ACK byte 0x06 stands alone between commands. A stray ``#``
between commands is dropped silently (Stellarium sends one before each command to flush the
handset), and any other byte between commands is reported as :class:`StrayBytes` and skipped, so
clients can stack commands back to back and line noise loses nothing but itself. A command longer
than :data:`MAX_COMMAND_LENGTH` is cut off and reported as malformed; the stream picks up again
at the next ``#``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from scopelink.protocol.base import NEED_DATA, Event, NeedData
from scopelink.protocol.lx200.commands import (
    ACK_BYTE,
    Ack,
    AnyCommand,
    MalformedCommand,
    UnknownCommand,
    parse_command,
)

__all__ = [
    "MAX_COMMAND_LENGTH",
    "NEED_DATA",
    "LX200ServerConnection",
    "NeedData",
    "StrayBytes",
]

MAX_COMMAND_LENGTH: Final = 40
"""Longest command text between ``:`` and ``#`` (the longest real one, a site name, is ~20)."""

_COLON = ord(":")
_HASH = ord("#")


@dataclass(frozen=True, slots=True)
class StrayBytes(Event):
    """Bytes between commands that start none; they were skipped."""

    data: bytes

    def describe(self) -> str:
        return f"{len(self.data)} stray byte(s) {self.data!r} between commands, skipped"


ServerEvent = AnyCommand | UnknownCommand | MalformedCommand | StrayBytes


class LX200ServerConnection:
    """Feed it the bytes from the client; take commands (and error events) with
    :meth:`next_event`. Never raises on input."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._skipping_overlong = False

    def receive_data(self, data: bytes) -> None:
        self._buffer += data

    @property
    def pending(self) -> bool:
        """Whether an incomplete command is held back."""
        return bool(self._buffer) or self._skipping_overlong

    def discard_partial(self) -> bytes:
        """Drop and return an incomplete command (after the line went quiet)."""
        dropped = bytes(self._buffer)
        self._buffer.clear()
        self._skipping_overlong = False
        return dropped

    def next_event(self) -> ServerEvent | NeedData:
        buffer = self._buffer
        if self._skipping_overlong:
            end = buffer.find(_HASH)
            if end < 0:
                buffer.clear()
                return NEED_DATA
            del buffer[: end + 1]
            self._skipping_overlong = False
        while buffer and buffer[0] == _HASH:
            del buffer[0]
        if not buffer:
            return NEED_DATA
        first = buffer[0]
        if first == ACK_BYTE:
            del buffer[0]
            return Ack()
        if first != _COLON:
            stray = 0
            while stray < len(buffer) and buffer[stray] not in (_COLON, _HASH, ACK_BYTE):
                stray += 1
            data = bytes(buffer[:stray])
            del buffer[:stray]
            return StrayBytes(data)
        end = buffer.find(_HASH)
        if end < 0:
            if len(buffer) - 1 > MAX_COMMAND_LENGTH:
                text = bytes(buffer[1:]).decode("latin-1")
                buffer.clear()
                self._skipping_overlong = True
                return MalformedCommand(text[:2], text, "command too long; skipped to its '#'")
            return NEED_DATA
        text = bytes(buffer[1:end]).decode("latin-1")
        del buffer[: end + 1]
        if len(text) > MAX_COMMAND_LENGTH:
            return MalformedCommand(text[:2], text, "command too long")
        return parse_command(text)
