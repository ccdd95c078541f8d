"""Incremental framing of Stellarium telescope messages, for the server and the client side.

Frames are cut by their LENGTH field. A frame of a sane length but an unknown type, or of a
known type with the wrong length, is skipped whole (:class:`SkippedMessage`): the stream stays in
step. A LENGTH below the 4-byte header or above :data:`MAX_MESSAGE_LENGTH` means the stream can no
longer be framed (:class:`BadLength`): the connection is then broken for good and the I/O layer
should drop the peer, as Stellarium's own server does.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Final

from scopelink.protocol.base import NEED_DATA, Event, NeedData
from scopelink.protocol.stellarium.messages import (
    CURRENT_POSITION_LENGTH,
    GOTO_LENGTH,
    HEADER_LENGTH,
    MESSAGE_TYPE_POSITION,
    CurrentPosition,
    GotoMessage,
)

__all__ = [
    "MAX_MESSAGE_LENGTH",
    "NEED_DATA",
    "BadLength",
    "NeedData",
    "SkippedMessage",
    "StellariumClientConnection",
    "StellariumServerConnection",
]

MAX_MESSAGE_LENGTH: Final = 120
"""Longest frame accepted (Stellarium's reference server reads into a buffer of this size)."""

_HEADER = struct.Struct("<HH")


@dataclass(frozen=True, slots=True)
class SkippedMessage(Event):
    """A well-framed message this side does not understand; it was skipped whole."""

    message_type: int
    frame: bytes
    reason: str

    def describe(self) -> str:
        size = len(self.frame)
        return f"skipped a {size}-byte message of type {self.message_type}: {self.reason}"


@dataclass(frozen=True, slots=True)
class BadLength(Event):
    """A LENGTH field no message can have: the stream is out of step and the peer must go."""

    length: int
    offset: int
    """Stream offset of the LENGTH field."""

    def describe(self) -> str:
        return (
            f"impossible message length {self.length} at offset {self.offset} (must lie in "
            f"[{HEADER_LENGTH}, {MAX_MESSAGE_LENGTH}]): the stream cannot be framed any more"
        )


class _FrameReader:
    """Cuts the byte stream into frames by their LENGTH field."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._offset = 0
        self.broken: BadLength | None = None

    def receive_data(self, data: bytes) -> None:
        if self.broken is None:
            self._buffer += data

    @property
    def pending(self) -> int:
        """Bytes of an incomplete frame held back."""
        return len(self._buffer)

    def next_frame(self) -> tuple[int, bytes] | BadLength | NeedData:
        if self.broken is not None or len(self._buffer) < HEADER_LENGTH:
            return NEED_DATA
        length, message_type = _HEADER.unpack_from(self._buffer)
        if not HEADER_LENGTH <= length <= MAX_MESSAGE_LENGTH:
            self.broken = BadLength(length, self._offset)
            self._buffer.clear()
            return self.broken
        if len(self._buffer) < length:
            return NEED_DATA
        frame = bytes(self._buffer[:length])
        del self._buffer[:length]
        self._offset += length
        return message_type, frame


class _Connection:
    """What both sides share: the frame reader, and the message type and length they expect."""

    def __init__(self) -> None:
        self._reader = _FrameReader()

    @property
    def broken(self) -> bool:
        return self._reader.broken is not None

    def receive_data(self, data: bytes) -> None:
        self._reader.receive_data(data)

    def _next_body(self, length: int, what: str) -> bytes | SkippedMessage | BadLength | NeedData:
        """The next frame if it is a position-type message of ``length`` bytes (``what``: its
        name in the reason a frame is skipped)."""
        frame = self._reader.next_frame()
        if not isinstance(frame, tuple):
            return frame
        message_type, data = frame
        if message_type != MESSAGE_TYPE_POSITION:
            return SkippedMessage(message_type, data, "unknown message type")
        if len(data) != length:
            return SkippedMessage(
                message_type, data, f"a {what} is {length} bytes long, not {len(data)}"
            )
        return data


class StellariumServerConnection(_Connection):
    """The telescope-server side: gotos in, current positions out."""

    @property
    def pending(self) -> int:
        return self._reader.pending

    def next_event(self) -> GotoMessage | SkippedMessage | BadLength | NeedData:
        """The next goto, a skipped frame, the fatal :class:`BadLength`, or NEED_DATA."""
        body = self._next_body(GOTO_LENGTH, "goto")
        return GotoMessage.decode(body) if isinstance(body, bytes) else body

    def send(self, position: CurrentPosition) -> bytes:
        return position.encode()


class StellariumClientConnection(_Connection):
    """The planetarium side (what Stellarium does): gotos out, current positions in."""

    def next_event(self) -> CurrentPosition | SkippedMessage | BadLength | NeedData:
        body = self._next_body(CURRENT_POSITION_LENGTH, "position")
        return CurrentPosition.decode(body) if isinstance(body, bytes) else body

    def send(self, goto: GotoMessage) -> bytes:
        return goto.encode()
