"""Sky Tracker state machines: the device (server) and the PC (client), bus handling included.

Commands are framed by length: one byte, except ``S`` (+8 bytes) and ``K`` (+2 bytes). While the PC
holds the Sky Commander bus (after ``Q`` answered ``A``) the Sky Tracker relays every byte to the
Sky Commander until ``q``, which ends the grant and is not relayed.
"""

from __future__ import annotations

import enum

from scopelink.protocol.base import NEED_DATA, PAUSED, LocalProtocolError, Wait

from .commander_messages import CommanderCommand
from .messages import (
    PAYLOAD_SIZES,
    SINGLE_BYTE_COMMANDS,
    BusAnswer,
    RelayToCommander,
    ReleaseBus,
    RequestBus,
    TrackerCommand,
    decode_payload_command,
)
from .stream import ByteStream, ReplyReader
from .wire import BadReply, IncompleteFrame, Reply, StrayByte, UnknownCommand

_RELEASE = ord("q")

TrackerServerEvent = TrackerCommand | RelayToCommander | UnknownCommand
TrackerClientEvent = Reply | StrayByte | BadReply


class BusState(enum.Enum):
    """Who may talk to the Sky Commander."""

    RELEASED = "released"
    """The Sky Tracker owns the Sky Commander; PC bytes are Sky Tracker commands."""
    REQUESTED = "requested"
    """``Q`` sent or received, no answer yet."""
    HELD = "held"
    """Granted to the PC: bytes go to the Sky Commander until ``q``."""


class TrackerServer(ByteStream):
    """Device side: bytes from the PC -> Sky Tracker commands, or relay events while granted.

    On :class:`RequestBus` the parser pauses (``next_event`` returns PAUSED) until the device calls
    :meth:`grant` or :meth:`refuse`, because what follows depends on the answer.
    """

    def __init__(self) -> None:
        super().__init__()
        self._bus = BusState.RELEASED

    @property
    def bus(self) -> BusState:
        """Current bus state as the device sees it."""
        return self._bus

    def next_event(self) -> TrackerServerEvent | Wait:
        """The next command, relay chunk or error; NEED_DATA, or PAUSED awaiting grant/refuse."""
        if self._bus is BusState.REQUESTED:
            return PAUSED
        if not self._buffer:
            return NEED_DATA
        if self._bus is BusState.HELD:
            return self._next_relayed()
        code = self._buffer[0]
        command = SINGLE_BYTE_COMMANDS.get(code)
        if command is not None:
            self._consume(1)
            if isinstance(command, RequestBus):
                self._bus = BusState.REQUESTED
            return command
        payload_size = PAYLOAD_SIZES.get(code)
        if payload_size is None:
            offset, data = self._consume(1)
            return UnknownCommand(offset, data, "not a Sky Tracker command")
        if len(self._buffer) < 1 + payload_size:
            return NEED_DATA
        _, frame = self._consume(1 + payload_size)
        return decode_payload_command(code, frame[1:])

    def _next_relayed(self) -> RelayToCommander | ReleaseBus:
        release_at = self._buffer.find(_RELEASE)
        if release_at == 0:
            self._consume(1)
            self._bus = BusState.RELEASED
            return ReleaseBus()
        _, data = self._consume(release_at if release_at > 0 else len(self._buffer))
        return RelayToCommander(data)

    def grant(self) -> bytes:
        """Answer the pending ``Q`` with ``A``; following bytes are relayed until ``q``."""
        self._answer_request()
        self._bus = BusState.HELD
        return BusAnswer(granted=True).encode()

    def refuse(self) -> bytes:
        """Answer the pending ``Q`` with NUL (a GOTO is running); parsing resumes as commands."""
        self._answer_request()
        self._bus = BusState.RELEASED
        return BusAnswer(granted=False).encode()

    def _answer_request(self) -> None:
        if self._bus is not BusState.REQUESTED:
            raise LocalProtocolError(f"no bus request to answer (bus is {self._bus.value})")

    def release(self) -> None:
        """End a grant from the device side (e.g. the PC went silent); bytes are commands again."""
        self._bus = BusState.RELEASED

    def discard_partial(self) -> IncompleteFrame | None:
        """Drop an unfinished ``S``/``K`` frame after an inter-byte timeout.

        Call it only after :meth:`next_event` returned NEED_DATA; returns what was dropped.
        """
        if not self._buffer or self._bus is not BusState.RELEASED:
            return None
        offset, data = self._consume(len(self._buffer))
        return IncompleteFrame(offset, data, "command payload incomplete after a pause")

    def send(self, reply: Reply) -> bytes:
        """The bytes of a reply to a Sky Tracker command (:meth:`grant`/:meth:`refuse` answer Q)."""
        if isinstance(reply, BusAnswer):
            raise LocalProtocolError("answer a bus request with grant() or refuse()")
        return reply.encode()


class TrackerClient(ReplyReader):
    """PC side: Sky Tracker commands, and Sky Commander commands inside a bus grant.

    ``send(RequestBus())`` then a :class:`BusAnswer` event; while the bus is held only Sky
    Commander commands and :class:`ReleaseBus` may be sent, otherwise only Sky Tracker commands.
    """

    def __init__(self) -> None:
        super().__init__()
        self._bus = BusState.RELEASED

    @property
    def bus(self) -> BusState:
        """Current bus state as the PC sees it."""
        return self._bus

    def send(self, command: TrackerCommand | CommanderCommand) -> bytes:
        """Bytes for ``command``; raises LocalProtocolError when the bus state forbids it."""
        self._check_idle(command)
        if isinstance(command, ReleaseBus):
            # Allowed even when not held, so a driver unsure of the device's state can make sure.
            self._bus = BusState.RELEASED
        elif isinstance(command, CommanderCommand):
            if self._bus is not BusState.HELD:
                raise LocalProtocolError(
                    f"cannot send {command.describe()!r} to the Sky Commander without the bus: "
                    "send RequestBus() and wait for the grant"
                )
        elif self._bus is BusState.HELD:
            raise LocalProtocolError(
                f"cannot send {command.describe()!r} to the Sky Tracker while holding the bus "
                "(it would be relayed to the Sky Commander): send ReleaseBus() first"
            )
        elif isinstance(command, RequestBus):
            self._bus = BusState.REQUESTED
        return self._start(command)

    def next_event(self) -> TrackerClientEvent | Wait:
        """The next reply, error, or NEED_DATA."""
        event = self._next_reply()
        if self._bus is BusState.REQUESTED and event is not NEED_DATA:
            granted = isinstance(event, BusAnswer) and event.granted
            # After a garbled answer the bus state is unknown; RELEASED lets the driver send 'q'.
            self._bus = BusState.HELD if granted else BusState.RELEASED
        return event

    def abandon_reply(self) -> None:
        """Stop waiting for the pending reply after a timeout. An unanswered ``Q`` leaves the bus
        RELEASED on our side; send ``ReleaseBus()`` in case the device did grant it."""
        super().abandon_reply()
        if self._bus is BusState.REQUESTED:
            self._bus = BusState.RELEASED
