"""SynScan connections in the style of h11: bring your own I/O, feed bytes in, take events out.

`SynScanClientConnection` is the PC side (a driver): one command in flight, its reply parsed by
shape. `SynScanServerConnection` is the hand-control side (an emulator or bridge): commands framed
by length, replies checked against the command they answer."""

from __future__ import annotations

from collections import deque
from enum import Enum
from typing import cast

from scopelink.protocol.base import NEED_DATA, LocalProtocolError, NeedData
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.commands import Echo
from scopelink.protocol.synscan.events import (
    ClientError,
    MalformedReply,
    ServerError,
    UnexpectedData,
)
from scopelink.protocol.synscan.message import Mismatch
from scopelink.protocol.synscan.parser import CommandParser
from scopelink.protocol.synscan.tables import AnyCommand, AnyReply, reply_fits


class ClientState(Enum):
    """Where the client connection stands."""

    IDLE = "idle"
    """No command in flight; `send` may be called."""
    AWAITING_REPLY = "awaiting reply"
    """One command sent, its reply not complete yet."""
    ERROR = "error"
    """A reply did not fit; call `reset` (and resynchronise) before sending again."""


# The states as plain module names: looking a member up on its Enum class runs a descriptor in
# Python 3.11 (about three times a dict look-up's cost), and a driver's every command reads and
# sets the state three times (issue #14: CPU per command).
_IDLE, _AWAITING_REPLY, _ERROR = ClientState.IDLE, ClientState.AWAITING_REPLY, ClientState.ERROR


class SynScanClientConnection:
    """The PC side of a SynScan link: one command in flight, its reply read by exact length and
    shape.

    Bytes received before a command is sent are never read as its reply: `next_event` reports them
    as `UnexpectedData` first.

    After `reset` (the driver timed out or saw a malformed reply) the connection is resynchronising:
    while the first `Echo` sent after it waits for its reply, bytes before the echoed byte + ``#``
    are reported as `UnexpectedData` instead of failing the reply, so late replies to earlier
    commands drain.

    The last reply to each polling command (`Command.repeats_reply`) is kept with its bytes:
    the same bytes to the same command give the same reply object again, unparsed (issue #14:
    CPU per command)."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._in_flight: AnyCommand | None = None
        self._last_replies: dict[bytes, tuple[bytes, AnyReply]] = {}
        """By command bytes: the last reply to a `Command.repeats_reply` poll, with its bytes."""
        self._last: tuple[bytes, AnyReply] | None = None
        """The remembered reply to the command in flight, if any (looked up once, by `send`)."""
        self._state = _IDLE
        self._resynchronising = False
        self._stale = b""

    @property
    def state(self) -> ClientState:
        """The current state."""
        return self._state

    @property
    def in_flight(self) -> AnyCommand | None:
        """The command whose reply is awaited, if any."""
        return self._in_flight

    def send(self, command: AnyCommand) -> bytes:
        """The bytes to write for ``command``; it becomes the command in flight."""
        if self._state is not _IDLE:
            raise LocalProtocolError(
                f"cannot send {command.describe()!r} while {self._state.value}"
                + (f" ({self._in_flight.describe()!r})" if self._in_flight else "; call reset()")
            )
        data = command.encode()
        if self._buffer:
            # these bytes arrived before the command was written, so they cannot be its reply
            self._stale += self._take(len(self._buffer))
        self._in_flight = command
        self._state = _AWAITING_REPLY
        self._last = self._last_replies.get(data)  # only repeats_reply polls are kept
        return data

    def receive_data(self, data: bytes) -> None:
        """Append bytes read from the link."""
        self._buffer += data

    def receive_and_next_event(self, data: bytes) -> AnyReply | ClientError | NeedData:
        """`receive_data` then `next_event`, in one call (a driver's reader runs it as each
        chunk arrives)."""
        last = self._last
        if last is not None and data == last[0] and not self._buffer and not self._stale:
            # The common case of a poll, first: the whole reply in this chunk, the same bytes
            # as last time, so the same reply, without buffering or scanning (issue #14).
            self._in_flight = self._last = None
            self._state = _IDLE
            self._resynchronising = False
            return last[1]
        self._buffer += data
        return self.next_event()

    def next_event(self) -> AnyReply | ClientError | NeedData:
        """The reply to the command in flight, an error event, or `NEED_DATA`."""
        if self._stale:
            stale, self._stale = self._stale, b""
            return UnexpectedData(stale)
        if not self._buffer:
            return NEED_DATA
        if self._in_flight is None:
            return UnexpectedData(self._take(len(self._buffer)))
        command = self._in_flight
        if self._resynchronising and isinstance(command, Echo):
            skip = _bytes_before_echo(self._buffer, command.value)
            if skip:
                return UnexpectedData(self._take(skip))
        buffer = self._buffer
        if (last := self._last) is not None:
            raw, reply = last
            if buffer.startswith(raw):  # the same bytes as last time: the same reply
                del buffer[: len(raw)]
                self._in_flight = self._last = None
                self._state = _IDLE
                self._resynchronising = False
                return reply
        result = command.scan_reply(buffer)
        if result is NEED_DATA:
            return NEED_DATA
        self._in_flight = self._last = None
        if isinstance(result, Mismatch):
            self._state = _ERROR
            return MalformedReply(
                command, self._take(result.index + 1), result.index, result.reason
            )
        reply = cast(AnyReply, result.reply)  # every Reply class is in AnyReply (tests check)
        if command.repeats_reply:  # remembered by the command's bytes
            self._last_replies[command.encode()] = (bytes(buffer[: result.length]), reply)
        del buffer[: result.length]  # the reply's bytes: parsed, not needed as bytes
        self._state = _IDLE
        self._resynchronising = False
        return reply

    def reset(self) -> bytes:
        """Forget the command in flight and drop buffered bytes (returned); start
        resynchronising."""
        self._in_flight = self._last = None
        self._state = _IDLE
        self._resynchronising = True
        dropped, self._stale = self._stale + self._take(len(self._buffer)), b""
        return dropped

    def _take(self, count: int) -> bytes:
        taken = bytes(self._buffer[:count])
        del self._buffer[:count]
        return taken


def _bytes_before_echo(buffer: bytearray, value: int) -> int:
    """How many leading bytes cannot begin the echo reply ``value #``."""
    for index, byte in enumerate(buffer):
        if byte == value and (index + 1 == len(buffer) or buffer[index + 1] == HASH):
            return index
    return len(buffer)


class SynScanServerConnection:
    """The hand-control side of a SynScan link: commands framed by length, replies answered in
    order.

    Every command `next_event` returns awaits a reply: `send` encodes it after checking that it is a
    reply that command can have; `skip_reply` leaves a command unanswered (a device that ignores it,
    or an injected fault)."""

    def __init__(self) -> None:
        self._parser = CommandParser()
        self._unanswered: deque[AnyCommand] = deque()

    @property
    def parser(self) -> CommandParser:
        """The underlying parser (stream offsets, pending bytes)."""
        return self._parser

    @property
    def unanswered(self) -> tuple[AnyCommand, ...]:
        """Commands returned by `next_event` and not yet answered, oldest first."""
        return tuple(self._unanswered)

    def receive_data(self, data: bytes) -> None:
        """Append bytes read from the link."""
        self._parser.receive_data(data)

    def next_event(self) -> AnyCommand | ServerError | NeedData:
        """The next command, an error event, or `NEED_DATA`; never raises."""
        event = self._parser.next_event()
        if not isinstance(event, ServerError) and event is not NEED_DATA:
            self._unanswered.append(event)
        return event

    def discard_partial(self) -> bytes:
        """Drop and return an incomplete frame (the I/O layer calls it after an inter-byte
        timeout)."""
        return self._parser.discard_partial()

    def send(self, reply: AnyReply) -> bytes:
        """The bytes that answer the oldest unanswered command with ``reply``."""
        if not self._unanswered:
            raise LocalProtocolError(f"no command awaits a reply; cannot send {reply.describe()!r}")
        command = self._unanswered[0]
        if not reply_fits(command, reply):
            raise LocalProtocolError(
                f"{type(reply).__name__} {reply.describe()!r} cannot answer {command.describe()!r}"
            )
        self._unanswered.popleft()
        return reply.encode()

    def skip_reply(self) -> AnyCommand:
        """Leave the oldest unanswered command without a reply; returns it."""
        if not self._unanswered:
            raise LocalProtocolError("no command awaits a reply")
        return self._unanswered.popleft()
