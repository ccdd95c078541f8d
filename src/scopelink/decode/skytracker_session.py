"""Annotating a Sky Tracker trace (the Sky Commander behind its bus), or a Sky Commander alone.

PC bytes go through the codec's `TrackerServer`; while it holds the bus for the PC, the bytes it
relays go through a `CommanderServer`. Each command's reply is read by a `TrackerClient` or
`CommanderClient` that was sent that command. The device's answer to ``Q`` (``A`` or NUL) is what
lets the `TrackerServer` go on: it grants or refuses as the trace says.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from scopelink.decode.model import Direction, Kind, Peer
from scopelink.decode.session import Session
from scopelink.protocol import skytracker as st
from scopelink.protocol.skytracker.messages import RelayToCommander

_Reader = st.TrackerClient | st.CommanderClient


@dataclass(slots=True)
class _AwaitedReply:
    command: st.Command
    command_offset: int
    peer: Peer
    reader: _Reader
    data: bytearray = field(default_factory=bytearray)
    positions: list[int] = field(default_factory=list)


class _Substream:
    """The bytes one parser was fed, each with its place in the trace."""

    def __init__(self) -> None:
        self.data = bytearray()
        self.positions: list[int] = []
        self.annotated_until = 0
        self._base = 0  # parser offset of data[0]: taken bytes are forgotten (live links)

    def append(self, data: bytes, positions: list[int]) -> None:
        self.data += data
        self.positions += positions

    def take(self, until: int) -> tuple[bytes, list[int]]:
        """The bytes from the last take up to ``until`` (a parser offset), and their places."""
        start, self.annotated_until = self.annotated_until, until
        first, last = start - self._base, until - self._base
        taken = bytes(self.data[first:last]), self.positions[first:last]
        del self.data[:last]
        del self.positions[:last]
        self._base = until
        return taken


class SkyTrackerSession(Session):
    """``behind_bus=True``: PC <-> Sky Tracker (+ Sky Commander through the bus); ``False``: PC
    <-> Sky Commander on its own port."""

    def __init__(self, *, behind_bus: bool) -> None:
        super().__init__()
        self._behind_bus = behind_bus
        self._tracker = st.TrackerServer()
        self._tracker_bytes = _Substream()
        self._commander = st.CommanderServer()
        self._commander_bytes = _Substream()
        self._awaited: deque[_AwaitedReply] = deque()

    def awaiting_reply(self) -> bool:
        return bool(self._awaited)

    # ------------------------------------------------------------------------------- commands

    def from_pc(self, byte: int, offset: int) -> None:
        self._flush_stray()
        if self._behind_bus:
            self._tracker.receive_data(bytes((byte,)))
            self._tracker_bytes.append(bytes((byte,)), [offset])
            self._drain_tracker()
        else:
            self._relay(bytes((byte,)), [offset])

    def _drain_tracker(self) -> None:
        while True:
            event = self._tracker.next_event()
            if isinstance(event, st.Wait):
                return
            raw, positions = self._tracker_bytes.take(self._tracker.offset)
            match event:
                case RelayToCommander(data):
                    self._relay(data, positions)
                case st.UnknownCommand():
                    self._emit(
                        positions,
                        raw,
                        Kind.ERROR,
                        f"unknown command byte: {event.reason}",
                        direction=Direction.PC,
                        peer=Peer.SKY_TRACKER,
                        error_offset=positions[0],
                    )
                case _:
                    self._emit(
                        positions,
                        raw,
                        Kind.COMMAND,
                        event.describe(),
                        direction=Direction.PC,
                        peer=Peer.SKY_TRACKER,
                        message=event,
                    )
                    if isinstance(event, st.ReleaseBus):
                        self._end_commander_line("cut short by 'q' (bus released)")
                    elif event.reply is not None:
                        self._await(event, positions[0], Peer.SKY_TRACKER)

    def _relay(self, data: bytes, positions: list[int]) -> None:
        self._commander.receive_data(data)
        self._commander_bytes.append(data, positions)
        while True:
            event = self._commander.next_event()
            if isinstance(event, st.Wait):
                return
            raw, taken = self._commander_bytes.take(self._commander.offset)
            if isinstance(event, st.ErrorEvent):
                self._emit(
                    taken,
                    raw,
                    Kind.ERROR,
                    event.reason,
                    direction=Direction.PC,
                    peer=Peer.SKY_COMMANDER,
                    error_offset=taken[0],
                )
                continue
            self._emit(
                taken,
                raw,
                Kind.COMMAND,
                event.describe(),
                direction=Direction.PC,
                peer=Peer.SKY_COMMANDER,
                message=event,
            )
            if event.reply is not None:
                self._await(event, taken[0], Peer.SKY_COMMANDER)

    def _await(
        self, command: st.TrackerCommand | st.CommanderCommand, command_offset: int, peer: Peer
    ) -> None:
        """A reader that was sent ``command`` reads its reply exactly as a driver would."""
        reader: _Reader
        if isinstance(command, st.CommanderCommand):
            reader = st.CommanderClient()
            reader.send(command)
        else:
            reader = st.TrackerClient()
            reader.send(command)
        self._awaited.append(_AwaitedReply(command, command_offset, peer, reader))

    def _end_commander_line(self, why: str) -> None:
        """An unfinished ``L`` line can never end now: report it."""
        dropped = self._commander.discard_partial()
        if dropped is None:
            return
        raw, positions = self._commander_bytes.take(self._commander.offset)
        self._emit(
            positions,
            raw,
            Kind.ERROR,
            f"incomplete Sky Commander line: {why}",
            direction=Direction.PC,
            peer=Peer.SKY_COMMANDER,
            error_offset=positions[-1],
        )

    # -------------------------------------------------------------------------------- replies

    def from_device(self, byte: int, offset: int) -> None:
        if not self._awaited:
            held = self._tracker.bus is st.BusState.HELD or not self._behind_bus
            self._stray_byte(byte, offset, Peer.SKY_COMMANDER if held else Peer.SKY_TRACKER)
            return
        awaited = self._awaited[0]
        awaited.reader.receive_data(bytes((byte,)))
        awaited.data.append(byte)
        awaited.positions.append(offset)
        event = awaited.reader.next_event()
        if isinstance(event, st.Wait):
            return
        self._awaited.popleft()
        if isinstance(event, st.ErrorEvent):
            self._emit(
                awaited.positions,
                bytes(awaited.data),
                Kind.ERROR,
                event.reason,
                direction=Direction.DEVICE,
                peer=awaited.peer,
                error_offset=awaited.positions[0],
                answers=awaited.command_offset,
            )
        else:
            self._emit(
                awaited.positions,
                bytes(awaited.data),
                Kind.REPLY,
                event.describe(),
                direction=Direction.DEVICE,
                peer=awaited.peer,
                message=event,
                answers=awaited.command_offset,
            )
        if isinstance(awaited.command, st.RequestBus):
            self._answer_bus_request(isinstance(event, st.BusAnswer) and event.granted)

    def _answer_bus_request(self, granted: bool) -> None:
        """Let the paused `TrackerServer` go on as the trace answered (a garbled or missing answer
        counts as refused, as the codec's PC side does)."""
        if granted:
            self._tracker.grant()
        else:
            self._tracker.refuse()
        self._drain_tracker()

    def _close_awaited(self, offset: int, why_absent: str, why_cut: str) -> None:
        while self._awaited:
            awaited = self._awaited.popleft()
            what = awaited.command.describe()
            if awaited.data:
                reply = awaited.command.reply
                size = f" of {reply.size}" if reply is not None else ""
                self._emit(
                    awaited.positions,
                    bytes(awaited.data),
                    Kind.ERROR,
                    f"incomplete reply to {what!r}: {len(awaited.data)}{size} bytes {why_cut}",
                    direction=Direction.DEVICE,
                    peer=awaited.peer,
                    error_offset=awaited.positions[-1],
                    answers=awaited.command_offset,
                )
            else:
                self._note_absent(
                    offset,
                    awaited.peer,
                    f"no reply to {what!r} {why_absent}",
                    awaited.command_offset,
                )
            if isinstance(awaited.command, st.RequestBus):
                self._answer_bus_request(granted=False)

    def finish(self, offset: int) -> None:
        self._flush_stray()
        self._close_awaited(offset, "in the trace", "before the end of the trace")
        dropped = self._tracker.discard_partial()
        if dropped is not None:
            raw, positions = self._tracker_bytes.take(self._tracker.offset)
            self._emit(
                positions,
                raw,
                Kind.ERROR,
                f"incomplete {chr(raw[0])!r} command: {len(raw)} bytes before the end of the trace",
                direction=Direction.PC,
                peer=Peer.SKY_TRACKER,
                error_offset=positions[-1],
            )
        self._end_commander_line("no carriage return before the end of the trace")
