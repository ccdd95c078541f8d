"""The spec's operating examples, through PC client, Sky Tracker server and Sky Commander server
wired together byte for byte."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from scopelink.protocol.skytracker import (
    PAUSED,
    Acknowledge,
    BusAnswer,
    BusState,
    CommanderClient,
    CommanderCommand,
    CommanderServer,
    LoadObject,
    LocalProtocolError,
    OffsetsReply,
    RatesReply,
    ReadOffsets,
    ReadRates,
    Realign,
    RelayToCommander,
    ReleaseBus,
    Reply,
    RequestBus,
    SelectMode,
    TrackerClient,
    TrackerCommand,
    TrackerMode,
    TrackerServer,
)
from tests.support.skytracker_codec import drain


@dataclass
class Wiring:
    """A PC, a Sky Tracker and a Sky Commander; records every byte on the PC line."""

    pc: TrackerClient = field(default_factory=TrackerClient)
    tracker: TrackerServer = field(default_factory=TrackerServer)
    commander: CommanderServer = field(default_factory=CommanderServer)
    pc_to_tracker: bytearray = field(default_factory=bytearray)
    tracker_to_pc: bytearray = field(default_factory=bytearray)
    tracker_saw: list[object] = field(default_factory=list)
    commander_saw: list[object] = field(default_factory=list)
    goto_running: bool = False

    def send(self, command: TrackerCommand | CommanderCommand) -> list[object]:
        """PC sends ``command``; devices react; returns the events the PC then reads."""
        wire = self.pc.send(command)
        self.pc_to_tracker += wire
        self.tracker.receive_data(wire)
        for event in drain(self.tracker, on_pause=self._answer_bus_request):
            self.tracker_saw.append(event)
            if isinstance(event, RelayToCommander):
                self.commander.receive_data(event.data)
                for request in drain(self.commander):
                    self.commander_saw.append(request)
                    self._commander_answers(request)
        return drain(self.pc)

    def _answer_bus_request(self) -> None:
        self._to_pc(self.tracker.refuse() if self.goto_running else self.tracker.grant())

    def _commander_answers(self, request: object) -> None:
        if isinstance(request, LoadObject):
            self._to_pc(self.commander.send(Acknowledge()))  # relayed back unchanged

    def _to_pc(self, data: bytes) -> None:
        self.tracker_to_pc += data
        self.pc.receive_data(data)


def test_operating_example_upload_current_object_then_goto() -> None:
    wiring = Wiring()
    assert wiring.send(RequestBus()) == [BusAnswer(granted=True)]
    assert wiring.send(LoadObject.current(12.345, 67.890)) == [Acknowledge()]
    assert wiring.send(ReleaseBus()) == []
    assert wiring.send(SelectMode(TrackerMode.GOTO)) == []

    assert bytes(wiring.pc_to_tracker) == b"QL99 12.345 +67.890\rqG"
    assert bytes(wiring.tracker_to_pc) == b"AA"
    assert wiring.tracker_saw == [
        RequestBus(),
        RelayToCommander(b"L99 12.345 +67.890\r"),
        ReleaseBus(),
        SelectMode(TrackerMode.GOTO),
    ]
    assert wiring.commander_saw == [LoadObject(99, 12.345, 67.89)]  # 'q' never reaches it


def test_realign_example_sends_n_before_releasing_the_bus() -> None:
    wiring = Wiring()
    wiring.send(RequestBus())
    wiring.send(LoadObject.current(12.345, 67.890))
    assert wiring.send(Realign()) == []
    wiring.send(ReleaseBus())

    assert bytes(wiring.pc_to_tracker) == b"QL99 12.345 +67.890\rNq"
    assert wiring.commander_saw == [LoadObject(99, 12.345, 67.89), Realign()]
    assert wiring.tracker.bus is BusState.RELEASED
    assert wiring.pc.bus is BusState.RELEASED


def test_bus_refused_during_goto_keeps_commander_commands_local() -> None:
    wiring = Wiring(goto_running=True)
    assert wiring.send(RequestBus()) == [BusAnswer(granted=False)]
    assert bytes(wiring.tracker_to_pc) == b"\x00"
    with pytest.raises(LocalProtocolError):
        wiring.send(Realign())
    assert wiring.commander_saw == []


def test_whole_pc_stream_at_once_pauses_at_q_until_the_device_answers() -> None:
    tracker = TrackerServer()
    tracker.receive_data(b"QL99 12.345 +67.890\rqG")
    assert tracker.next_event() == RequestBus()
    assert tracker.next_event() is PAUSED
    tracker.grant()
    assert drain(tracker) == [
        RelayToCommander(b"L99 12.345 +67.890\r"),
        ReleaseBus(),
        SelectMode(TrackerMode.GOTO),
    ]


def test_refused_stream_is_read_as_tracker_commands() -> None:
    tracker = TrackerServer()
    tracker.receive_data(b"QG")
    assert tracker.next_event() == RequestBus()
    tracker.refuse()
    assert drain(tracker) == [SelectMode(TrackerMode.GOTO)]


@pytest.mark.parametrize(
    ("command", "reply"),
    [(ReadOffsets(), OffsetsReply(-12.5, 3.25)), (ReadRates(), RatesReply(0.25, -0.125))],
)
def test_tracker_polls_the_commander_with_the_commander_client(
    command: CommanderCommand, reply: Reply
) -> None:
    poller, commander = CommanderClient(), CommanderServer()
    commander.receive_data(poller.send(command))
    assert drain(commander) == [command]
    poller.receive_data(commander.send(reply))
    assert drain(poller) == [reply]
