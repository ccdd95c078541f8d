"""Byte buffering with stream offsets, shared by the Sky Tracker and Sky Commander machines."""

from __future__ import annotations

from scopelink.protocol.base import NEED_DATA, LocalProtocolError, Wait

from .wire import BadReply, Command, Reply, StrayByte


class ByteStream:
    """Bytes received but not yet turned into events, and where they sit in the whole stream."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._offset = 0

    def receive_data(self, data: bytes) -> None:
        """Feed bytes received from the peer; call :meth:`next_event` until it returns a Wait."""
        self._buffer += data

    @property
    def offset(self) -> int:
        """Stream position of the first byte not yet consumed by an event."""
        return self._offset

    @property
    def has_data(self) -> bool:
        """Whether bytes are waiting to be turned into events (cheaper than :attr:`buffered`)."""
        return bool(self._buffer)

    @property
    def buffered(self) -> bytes:
        """Bytes received but not yet consumed by an event."""
        return bytes(self._buffer)

    def _consume(self, count: int) -> tuple[int, bytes]:
        """Remove ``count`` bytes from the front; return their stream offset and the bytes."""
        start = self._offset
        data = bytes(self._buffer[:count])
        del self._buffer[:count]
        self._offset += count
        return start, data


class ReplyReader(ByteStream):
    """The PC side of a one-command-in-flight protocol: replies read by exact length.

    Each command that has a reply yields exactly one event: the typed reply, or
    :class:`BadReply` when its bytes do not fit. Bytes arriving while no reply is expected come
    out one by one as :class:`StrayByte`.
    """

    def __init__(self) -> None:
        super().__init__()
        self._awaiting: Command | None = None

    @property
    def awaiting(self) -> Command | None:
        """The command whose reply has not arrived yet, if any."""
        return self._awaiting

    def abandon_reply(self) -> None:
        """Stop waiting for the pending reply (the driver timed out); late bytes become stray."""
        self._awaiting = None

    def _check_idle(self, command: Command) -> None:
        if self._awaiting is not None:
            raise LocalProtocolError(
                f"cannot send {command.describe()!r}: still waiting for the reply to "
                f"{self._awaiting.describe()!r} (read it, or abandon_reply() after a timeout)"
            )

    def _start(self, command: Command) -> bytes:
        self._check_idle(command)
        self._awaiting = command if command.reply is not None else None
        return command.encode()

    def _next_reply(self) -> Reply | StrayByte | BadReply | Wait:
        command = self._awaiting
        if command is None or command.reply is None:
            if not self._buffer:
                return NEED_DATA
            offset, data = self._consume(1)
            return StrayByte(offset, data, "byte from the device while no reply was expected")
        reply_type = command.reply
        if len(self._buffer) < reply_type.size:
            return NEED_DATA
        offset, data = self._consume(reply_type.size)
        self._awaiting = None
        try:
            return reply_type.decode(data)
        except ValueError as error:
            return BadReply(offset, data, f"reply to {command.describe()!r}: {error}")
