"""Sky Tracker command framing and both state machines (device server, PC client)."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.protocol.skytracker import (
    NEED_DATA,
    PAUSED,
    Acknowledge,
    BadReply,
    BusAnswer,
    BusState,
    CalibrationReply,
    Direction,
    GuideSpeedReply,
    IncompleteFrame,
    LocalProtocolError,
    PressDirection,
    ReadCalibration,
    ReadGuideSpeed,
    ReadPosition,
    ReadStatus,
    ReadVersion,
    RelayToCommander,
    ReleaseBus,
    ReleaseDirections,
    Reply,
    RequestBus,
    SelectMode,
    SetCalibration,
    SetGuideSpeed,
    StatusReply,
    StrayByte,
    TrackerClient,
    TrackerCommand,
    TrackerMode,
    TrackerServer,
    TrackerStatus,
    UnknownCommand,
    VersionReply,
)
from tests.support.skytracker_codec import (
    calfloat_values,
    canonical_calfloat_bytes,
    chunk_cuts,
    drain,
    feed,
    merge_relays,
    wire_length,
)

guide_speeds = st.integers(0, 255)

tracker_commands: st.SearchStrategy[TrackerCommand] = st.one_of(
    st.builds(SelectMode, st.sampled_from(TrackerMode)),
    st.builds(PressDirection, st.sampled_from([*Direction])),
    st.sampled_from(
        [ReleaseDirections(), ReadStatus(), ReadCalibration(), ReadVersion(), ReadGuideSpeed()]
    ),
    st.builds(SetCalibration, calfloat_values, calfloat_values),
    st.builds(SetGuideSpeed, guide_speeds, guide_speeds),
)
"""Every Sky Tracker command except the bus ones (tested through the bus machinery)."""

replies_by_command: dict[type[Reply], st.SearchStrategy[Reply]] = {
    StatusReply: st.builds(StatusReply, st.integers(0, 255).map(TrackerStatus.from_byte)),
    Acknowledge: st.just(Acknowledge()),
    CalibrationReply: st.builds(CalibrationReply, calfloat_values, calfloat_values),
    VersionReply: st.builds(
        VersionReply, st.text(st.characters(max_codepoint=127), min_size=8, max_size=8)
    ),
    GuideSpeedReply: st.builds(GuideSpeedReply, guide_speeds, guide_speeds),
    BusAnswer: st.builds(BusAnswer, st.booleans()),
}


# --- spec examples -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("wire", "command"),
    [
        (b"U", SelectMode(TrackerMode.UTILITY)),
        (b"T", SelectMode(TrackerMode.TRACK)),
        (b"D", SelectMode(TrackerMode.GUIDE)),
        (b"B", SelectMode(TrackerMode.STANDBY)),
        (b"G", SelectMode(TrackerMode.GOTO)),
        (b"u", PressDirection(Direction.UP)),
        (b"d", PressDirection(Direction.DOWN)),
        (b"l", PressDirection(Direction.LEFT)),
        (b"r", PressDirection(Direction.RIGHT)),
        (b"b", ReleaseDirections()),
        (b"R", ReadStatus()),
        (b"s", ReadCalibration()),
        (b"V", ReadVersion()),
        (b"k", ReadGuideSpeed()),
        (b"Q", RequestBus()),
        (b"q", ReleaseBus()),
        (b"S\x47\x81\xe2\x00\x48\x1c\x65\x80", SetCalibration(16625.0, 40037.5)),
        (b"K\x0a\x78", SetGuideSpeed(10, 120)),
    ],
)
def test_every_command_letter(wire: bytes, command: TrackerCommand) -> None:
    assert command.encode() == wire
    server = TrackerServer()
    server.receive_data(wire)
    assert server.next_event() == command
    assert command.describe().startswith(wire[:1].decode())


def test_version_reply_is_eight_characters() -> None:
    client = TrackerClient()
    assert client.send(ReadVersion()) == b"V"
    client.receive_data(b"v4.0   ")
    assert client.next_event() is NEED_DATA  # seven characters are not a reply yet
    client.receive_data(b" ")
    assert drain(client) == [VersionReply("v4.0    ")]
    assert VersionReply.padded("v4.0").encode() == b"v4.0    "
    with pytest.raises(ValueError, match="8 ASCII"):
        VersionReply("v4.0")


def test_guide_speed_set_has_no_reply_and_reads_back_as_two_bytes() -> None:
    client, server = TrackerClient(), TrackerServer()
    server.receive_data(client.send(SetGuideSpeed(30, 240)))
    assert drain(server) == [SetGuideSpeed(30, 240)]
    assert client.awaiting is None  # K expects nothing: the next command may follow at once
    server.receive_data(client.send(ReadGuideSpeed()))
    assert drain(server) == [ReadGuideSpeed()]
    client.receive_data(server.send(GuideSpeedReply(30, 240)))
    assert drain(client) == [GuideSpeedReply(30, 240)]
    with pytest.raises(ValueError, match="0-255"):
        SetGuideSpeed(256, 0)


def test_set_calibration_is_acknowledged_with_a() -> None:
    client = TrackerClient()
    client.send(SetCalibration(16625.0, 40037.5))
    client.receive_data(b"A")
    assert drain(client) == [Acknowledge()]


def test_bus_is_refused_with_nul_while_a_goto_runs() -> None:
    client, server = TrackerClient(), TrackerServer()
    server.receive_data(client.send(SelectMode(TrackerMode.GOTO)) + client.send(RequestBus()))
    assert drain(server) == [SelectMode(TrackerMode.GOTO), RequestBus()]
    assert server.next_event() is PAUSED
    answer = server.refuse()
    assert answer == b"\x00"
    assert server.bus is BusState.RELEASED
    client.receive_data(answer)
    assert drain(client) == [BusAnswer(granted=False)]
    assert client.bus is BusState.RELEASED
    with pytest.raises(LocalProtocolError, match="without the bus"):
        client.send(ReadPosition())


def waiting(client: TrackerClient) -> bool:
    """A function, so type checkers do not narrow the property between reads."""
    return client.has_data


def test_client_says_whether_bytes_wait() -> None:
    client = TrackerClient()
    assert not waiting(client)
    client.receive_data(b"\x10")  # a byte while no reply is expected: a stray, still waiting
    assert waiting(client)
    assert isinstance(client.next_event(), StrayByte)
    assert not waiting(client)
    client.send(ReadStatus())
    client.receive_data(b"\x90")
    assert waiting(client)
    assert isinstance(client.next_event(), StatusReply)
    assert not waiting(client)


def test_status_reply_describes_flags() -> None:
    client = TrackerClient()
    client.send(ReadStatus())
    client.receive_data(b"\x90")
    (event,) = drain(client)
    assert isinstance(event, StatusReply)
    assert "UTIL|GOTO" in str(event)


# --- server behaviour ----------------------------------------------------------------------


def test_unknown_bytes_are_reported_with_their_offset_and_parsing_continues() -> None:
    server = TrackerServer()
    server.receive_data(b"R\x00zT")
    assert drain(server) == [
        ReadStatus(),
        UnknownCommand(1, b"\x00", "not a Sky Tracker command"),
        UnknownCommand(2, b"z", "not a Sky Tracker command"),
        SelectMode(TrackerMode.TRACK),
    ]
    assert server.offset == 4


def test_payload_frames_wait_for_all_their_bytes() -> None:
    server = TrackerServer()
    server.receive_data(b"K\x10")
    assert server.next_event() is NEED_DATA
    server.receive_data(b"\x20R")
    assert drain(server) == [SetGuideSpeed(0x10, 0x20), ReadStatus()]


def test_discard_partial_drops_an_incomplete_frame_after_a_pause() -> None:
    server = TrackerServer()
    server.receive_data(b"RS\x47\x81")
    assert drain(server) == [ReadStatus()]
    assert server.discard_partial() == IncompleteFrame(
        1, b"S\x47\x81", "command payload incomplete after a pause"
    )
    assert server.discard_partial() is None
    server.receive_data(b"V")
    assert drain(server) == [ReadVersion()]
    assert server.offset == 5


def test_granted_bytes_are_relayed_until_q_which_is_not_relayed() -> None:
    server = TrackerServer()
    server.receive_data(b"Q")
    assert drain(server) == [RequestBus()]
    assert server.grant() == b"A"
    server.receive_data(b"O\rR")
    assert drain(server) == [RelayToCommander(b"O\rR")]
    server.receive_data(b"NqR")
    assert drain(server) == [RelayToCommander(b"N"), ReleaseBus(), ReadStatus()]
    assert server.bus is BusState.RELEASED


def test_server_bus_answers_need_a_request() -> None:
    server = TrackerServer()
    with pytest.raises(LocalProtocolError, match="no bus request"):
        server.grant()
    with pytest.raises(LocalProtocolError, match="grant"):
        server.send(BusAnswer(granted=True))


def test_device_can_end_a_grant_on_its_own() -> None:
    server = TrackerServer()
    server.receive_data(b"Q")
    drain(server)
    server.grant()
    server.release()
    server.receive_data(b"R")
    assert drain(server) == [ReadStatus()]


# --- client behaviour ----------------------------------------------------------------------


def test_client_refuses_tracker_commands_while_holding_the_bus() -> None:
    client = TrackerClient()
    client.send(RequestBus())
    client.receive_data(b"A")
    assert drain(client) == [BusAnswer(granted=True)]
    assert client.bus is BusState.HELD
    with pytest.raises(LocalProtocolError, match="while holding the bus"):
        client.send(ReadStatus())
    with pytest.raises(LocalProtocolError, match="while holding the bus"):
        client.send(RequestBus())
    assert client.send(ReleaseBus()) == b"q"
    assert client.send(ReadStatus()) == b"R"


def test_client_sends_one_command_at_a_time() -> None:
    client = TrackerClient()
    client.send(ReadStatus())
    with pytest.raises(LocalProtocolError, match="still waiting"):
        client.send(ReadVersion())


def test_abandoned_reply_makes_late_bytes_stray() -> None:
    client = TrackerClient()
    client.send(ReadStatus())
    client.abandon_reply()
    client.receive_data(b"\x80")
    assert drain(client) == [
        StrayByte(0, b"\x80", "byte from the device while no reply was expected")
    ]


def test_unanswered_bus_request_leaves_the_bus_released_so_q_can_be_sent() -> None:
    client = TrackerClient()
    client.send(RequestBus())
    client.abandon_reply()
    assert client.bus is BusState.RELEASED
    assert client.send(ReleaseBus()) == b"q"


def test_garbled_bus_answer_is_an_error_and_releases_the_bus() -> None:
    client = TrackerClient()
    client.send(RequestBus())
    client.receive_data(b"Z")
    (event,) = drain(client)
    assert isinstance(event, BadReply)
    assert event.offset == 0
    assert "'Q: request the Sky Commander bus'" in event.reason
    assert client.bus is BusState.RELEASED


# --- properties ----------------------------------------------------------------------------


@given(tracker_commands)
def test_commands_round_trip_client_to_server(command: TrackerCommand) -> None:
    client, server = TrackerClient(), TrackerServer()
    wire = client.send(command)
    server.receive_data(wire)
    assert drain(server) == [command]
    assert server.offset == len(wire)
    assert str(command) == command.describe()


@given(st.data())
def test_replies_round_trip_server_to_client(data: st.DataObject) -> None:
    command = data.draw(
        tracker_commands.filter(lambda c: c.reply is not None) | st.just(RequestBus())
    )
    assert command.reply is not None
    reply = data.draw(replies_by_command[command.reply])
    client = TrackerClient()
    client.send(command)
    wire = reply.encode() if isinstance(reply, BusAnswer) else TrackerServer().send(reply)
    assert len(wire) == command.reply.size
    assert feed(client, wire, range(len(wire))) == [reply]  # one byte at a time
    assert reply.describe()


@given(st.sampled_from([StatusReply, CalibrationReply, VersionReply, GuideSpeedReply]), st.data())
def test_reply_bytes_decode_and_re_encode_identically(
    reply_type: type[Reply], data: st.DataObject
) -> None:
    wire = data.draw(st.binary(min_size=reply_type.size, max_size=reply_type.size))
    if reply_type is CalibrationReply:
        wire = data.draw(canonical_calfloat_bytes) + data.draw(canonical_calfloat_bytes)
    elif reply_type is VersionReply:
        wire = bytes(b & 0x7F for b in wire)
    assert reply_type.decode(wire).encode() == wire


@given(st.lists(tracker_commands, max_size=12), st.data())
def test_server_parsing_is_the_same_for_any_chunking(
    commands: list[TrackerCommand], data: st.DataObject
) -> None:
    wire = b"".join(command.encode() for command in commands)
    server = TrackerServer()
    assert feed(server, wire, data.draw(chunk_cuts(len(wire)))) == commands
    one_by_one = TrackerServer()
    assert feed(one_by_one, wire, range(len(wire))) == commands


garbage = st.binary(max_size=80) | st.lists(
    st.sampled_from(b"QqSKRsVkUTDBGudlrb\x00A\r"), max_size=60
).map(bytes)


def _server_events(wire: bytes, cuts: Any, decisions: list[bool]) -> tuple[list[Any], int]:
    server = TrackerServer()
    answers = iter(decisions)

    def decide() -> None:
        (server.grant if next(answers, True) else server.refuse)()

    events = feed(server, wire, cuts, on_pause=decide)
    return merge_relays(events), server.offset + len(server.buffered)


@settings(max_examples=150)
@given(garbage, st.lists(st.booleans(), max_size=20), st.data())
def test_server_survives_garbage_and_accounts_for_every_byte(
    wire: bytes, decisions: list[bool], data: st.DataObject
) -> None:
    whole, seen = _server_events(wire, (), decisions)
    chunked, _ = _server_events(wire, data.draw(chunk_cuts(len(wire))), decisions)
    one_by_one, _ = _server_events(wire, range(len(wire)), decisions)
    assert whole == chunked == one_by_one
    assert seen == len(wire)
    position = 0
    for event in whole:
        if isinstance(event, UnknownCommand):
            assert event.offset == position
            assert wire[position : position + 1] == event.data
        position += wire_length(event)
    assert position <= len(wire) < position + 9  # only an unfinished S/K frame may be left


@settings(max_examples=150)
@given(garbage, st.data())
def test_client_survives_garbage_for_any_pending_command(wire: bytes, data: st.DataObject) -> None:
    command = data.draw(tracker_commands | st.just(RequestBus()))
    cuts = data.draw(chunk_cuts(len(wire)))
    runs = []
    for split in ((), cuts, range(len(wire))):
        client = TrackerClient()
        client.send(command)
        events = feed(client, wire, split)
        assert sum(wire_length(e) for e in events) == client.offset
        assert client.offset + len(client.buffered) == len(wire)
        runs.append(events)
    assert runs[0] == runs[1] == runs[2]
    assert len(client.buffered) < (command.reply.size if command.reply else 1)
