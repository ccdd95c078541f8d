"""Framing of the LX200 streams: commands on the handset's side (:class:`LX200ServerConnection`),
and replies on the planetarium's side (:class:`LX200ClientConnection`).

Commands run from ``:`` to ``#``; the ACK byte 0x06 stands alone between commands. A stray ``#``
between commands is dropped silently (Stellarium sends one before each command to flush the
handset), and any other byte between commands is reported as :class:`StrayBytes` and skipped, so
clients can stack commands back to back and line noise loses nothing but itself. A command longer
than :data:`MAX_COMMAND_LENGTH` is cut off and reported as malformed; the stream picks up again
at the next ``#``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Final

from scopelink.protocol.base import NEED_DATA, Event, NeedData
from scopelink.protocol.lx200.commands import (
    ACK_BYTE,
    Ack,
    AnyCommand,
    MalformedCommand,
    ReplyKind,
    UnknownCommand,
    encode_command,
    parse_command,
    reply_kind,
)

__all__ = [
    "MAX_COMMAND_LENGTH",
    "MAX_REPLY_LENGTH",
    "NEED_DATA",
    "LX200ClientConnection",
    "LX200Reply",
    "LX200ServerConnection",
    "MalformedReply",
    "NeedData",
    "StrayBytes",
    "UnexpectedReply",
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


MAX_REPLY_LENGTH: Final = 64
"""Longest reply text before its ``#`` (the longest real one, a product name, is ~20)."""


@dataclass(frozen=True, slots=True)
class LX200Reply(Event):
    """The reply to ``command``, as received (terminators included)."""

    command: AnyCommand
    data: bytes

    def describe(self) -> str:
        return f"reply {self.data!r} to {self.command!r}"


@dataclass(frozen=True, slots=True)
class UnexpectedReply(Event):
    """Bytes from the handset while no command waited for a reply; they were dropped."""

    data: bytes

    def describe(self) -> str:
        return f"{len(self.data)} byte(s) {self.data!r} with no command waiting, dropped"


@dataclass(frozen=True, slots=True)
class MalformedReply(Event):
    """A reply that cannot be the one ``command`` gets (too long without its ``#``)."""

    command: AnyCommand
    data: bytes
    reason: str

    def describe(self) -> str:
        return f"malformed reply {self.data!r} to {self.command!r}: {self.reason}"


ClientEvent = LX200Reply | UnexpectedReply | MalformedReply


class LX200ClientConnection:
    """The planetarium's end: :meth:`send` a command (its bytes to write), feed the handset's
    bytes to :meth:`receive_data`, take each reply with :meth:`next_event`, in the order the
    commands were sent. A reply is cut by the shape its command gets (:func:`reply_kind`): one
    character, text up to ``#``, a slew's ``0`` or ``1``/``2`` + text + ``#``, a date's ``0`` or
    ``1`` + two ``#`` strings. Never raises on input."""

    def __init__(self, *, high_precision: bool = True) -> None:
        self.high_precision = high_precision
        self._buffer = bytearray()
        self._waiting: deque[tuple[AnyCommand, ReplyKind]] = deque()

    def send(self, command: AnyCommand) -> bytes:
        kind = reply_kind(command)
        if kind is not ReplyKind.NONE:
            self._waiting.append((command, kind))
        return encode_command(command, high_precision=self.high_precision)

    def receive_data(self, data: bytes) -> None:
        self._buffer += data

    @property
    def waiting(self) -> int:
        """How many sent commands still wait for their reply."""
        return len(self._waiting)

    def next_event(self) -> ClientEvent | NeedData:
        buffer = self._buffer
        if not buffer:
            return NEED_DATA
        if not self._waiting:
            data = bytes(buffer)
            buffer.clear()
            return UnexpectedReply(data)
        command, kind = self._waiting[0]
        size = _reply_size(kind, buffer)
        if size is None:
            if len(buffer) > MAX_REPLY_LENGTH:
                self._waiting.popleft()
                data = bytes(buffer)
                buffer.clear()
                return MalformedReply(command, data, f"no '#' within {MAX_REPLY_LENGTH} bytes")
            return NEED_DATA
        self._waiting.popleft()
        data = bytes(buffer[:size])
        del buffer[:size]
        return LX200Reply(command, data)


def _reply_size(kind: ReplyKind, buffer: bytearray) -> int | None:
    """How many bytes of ``buffer`` the reply of shape ``kind`` takes, or None if not all came."""
    first = buffer[0]
    if kind is ReplyKind.CHAR:
        return 1
    if kind is ReplyKind.SLEW and first not in b"12":
        return 1  # '0': the slew started
    if kind is ReplyKind.DATE_SET and first != ord("1"):
        return 1  # '0': the date was refused
    end = -1
    for _ in range(2 if kind is ReplyKind.DATE_SET else 1):
        end = buffer.find(_HASH, end + 1)
        if end < 0:
            return None
    return end + 1
