"""Length-framed parsing of the PC -> hand control byte stream (the server side's reader).

A command is framed by the length its first letter implies (`FRAME_LENGTHS`), never by a
terminator. A malformed frame is discarded whole, so its payload bytes are never read as
commands."""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.protocol.base import NEED_DATA, NeedData
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.events import MalformedCommand, ServerError, UnknownCommand
from scopelink.protocol.synscan.message import FieldError
from scopelink.protocol.synscan.tables import AnyCommand, decode_command_frame, frame_length


@dataclass(frozen=True, slots=True)
class ParsedCommand:
    """A command with where it was in the stream and its exact bytes."""

    command: AnyCommand
    raw: bytes
    offset: int


class CommandParser:
    """Incremental, length-framed parser of the PC -> hand control byte stream.

    Feed bytes with `receive_data`; `next_frame` (or `next_event`) returns one command or error at a
    time, or `NEED_DATA`. A stray ``#`` between commands is skipped silently; an unknown byte gives
    `UnknownCommand` and is skipped; a malformed payload gives `MalformedCommand` and its whole
    frame is discarded. Never raises on any input."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._offset = 0

    @property
    def offset(self) -> int:
        """Stream offset of the first byte not yet consumed."""
        return self._offset

    @property
    def pending(self) -> bytes:
        """Bytes received but not yet consumed (the start of an incomplete frame)."""
        return bytes(self._buffer)

    def receive_data(self, data: bytes) -> None:
        """Append bytes read from the link."""
        self._buffer += data

    def next_frame(self) -> ParsedCommand | ServerError | NeedData:
        """The next command with its offset and raw bytes, an error event, or `NEED_DATA`."""
        while self._buffer and self._buffer[0] == HASH:
            self._consume(1)
        if not self._buffer:
            return NEED_DATA
        offset = self._offset
        length = frame_length(self._buffer[0])
        if length is None:
            return UnknownCommand(self._consume(1)[0], offset)
        if len(self._buffer) < length:
            return NEED_DATA
        frame = self._consume(length)
        parsed = decode_command_frame(frame)
        if isinstance(parsed, FieldError):
            return MalformedCommand(frame, parsed.index, offset, parsed.reason)
        return ParsedCommand(parsed, frame, offset)

    def next_event(self) -> AnyCommand | ServerError | NeedData:
        """The next command, an error event, or `NEED_DATA`."""
        event = self.next_frame()
        return event.command if isinstance(event, ParsedCommand) else event

    def discard_partial(self) -> bytes:
        """Drop and return an incomplete frame (call after an inter-byte timeout)."""
        return self._consume(len(self._buffer))

    def _consume(self, count: int) -> bytes:
        taken = bytes(self._buffer[:count])
        del self._buffer[:count]
        self._offset += count
        return taken
