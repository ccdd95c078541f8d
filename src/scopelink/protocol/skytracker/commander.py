"""Sky Commander state machines: the device (server) and the PC or Sky Tracker polling it (client).

Single-byte commands (``\\r``, ``N``, ``O``, ``R``) stand alone; an ``L`` line runs to its ``\\r``,
at most :data:`MAX_LINE_LENGTH` bytes, so garbage can never make the parser wait forever.
"""

from __future__ import annotations

from scopelink.protocol.base import NEED_DATA, Wait

from .commander_messages import SINGLE_BYTE_COMMANDS, CommanderCommand, LoadObject
from .stream import ByteStream, ReplyReader
from .wire import (
    BadReply,
    ErrorEvent,
    IncompleteFrame,
    LineTooLong,
    MalformedCommand,
    Reply,
    StrayByte,
    UnknownCommand,
)

MAX_LINE_LENGTH = 32
"""Longest ``L`` line accepted, CR included (a well-formed one is 19 bytes)."""

_LINE_START = ord("L")
_CR = ord("\r")

CommanderServerEvent = CommanderCommand | ErrorEvent
CommanderClientEvent = Reply | StrayByte | BadReply


class CommanderServer(ByteStream):
    """Device side: bytes from the PC (or relayed by the Sky Tracker) -> Sky Commander commands.

    After an over-long line it skips to the next ``\\r`` (which ends the bad line), reporting the
    skipped bytes as :class:`LineTooLong` in chunks of at most :data:`MAX_LINE_LENGTH` bytes.
    """

    def __init__(self) -> None:
        super().__init__()
        self._skipping_line = False

    def next_event(self) -> CommanderServerEvent | Wait:
        """The next command or error, or NEED_DATA."""
        if not self._buffer:
            return NEED_DATA
        if self._skipping_line:
            return self._skip_rest_of_line()
        first = self._buffer[0]
        command = SINGLE_BYTE_COMMANDS.get(first)
        if command is not None:
            self._consume(1)
            return command
        if first != _LINE_START:
            offset, data = self._consume(1)
            return UnknownCommand(offset, data, "not a Sky Commander command")
        end = self._buffer.find(_CR, 0, MAX_LINE_LENGTH)
        if end < 0:
            if len(self._buffer) < MAX_LINE_LENGTH:
                return NEED_DATA
            offset, data = self._consume(MAX_LINE_LENGTH)
            self._skipping_line = True
            return LineTooLong(
                offset, data, f"no CR within {MAX_LINE_LENGTH} bytes of 'L'; skipping to next CR"
            )
        offset, line = self._consume(end + 1)
        try:
            return LoadObject.decode(line)
        except ValueError as error:
            return MalformedCommand(offset, line, str(error))

    def _skip_rest_of_line(self) -> LineTooLong | Wait:
        end = self._buffer.find(_CR, 0, MAX_LINE_LENGTH)
        if end >= 0:
            self._skipping_line = False
            offset, data = self._consume(end + 1)
            return LineTooLong(offset, data, "end of over-long line")
        if len(self._buffer) < MAX_LINE_LENGTH:
            return NEED_DATA
        offset, data = self._consume(MAX_LINE_LENGTH)
        return LineTooLong(offset, data, "over-long line continues")

    def discard_partial(self) -> IncompleteFrame | None:
        """Drop an unfinished ``L`` line after an inter-byte timeout (the codec has no clock).

        The pause also ends an over-long line being skipped, even when its bytes so far were all
        reported already: what follows the pause is a new command, not the old line's tail."""
        self._skipping_line = False
        if not self._buffer:
            return None
        offset, data = self._consume(len(self._buffer))
        return IncompleteFrame(offset, data, "unfinished line dropped after a pause")

    def send(self, reply: Reply) -> bytes:
        """The bytes of a reply to the command last received."""
        return reply.encode()


class CommanderClient(ReplyReader):
    """PC side (or the Sky Tracker polling ``O``/``R``): one command in flight, read by length."""

    def send(self, command: CommanderCommand) -> bytes:
        """Bytes for ``command``; raises LocalProtocolError while a reply is still awaited."""
        return self._start(command)

    def next_event(self) -> CommanderClientEvent | Wait:
        """The next reply, error, or NEED_DATA."""
        return self._next_reply()
