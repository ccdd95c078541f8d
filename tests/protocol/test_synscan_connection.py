"""The SynScan client and server connections as state machines, and the two talking together."""

from __future__ import annotations

import pytest

from scopelink.protocol.synscan import (
    NEED_DATA,
    Ack,
    AnyCommand,
    AnyReply,
    Axis,
    CancelGoto,
    ClientState,
    Echo,
    EchoReply,
    FixedRateSlew,
    Frame,
    GetLocation,
    GetModel,
    GetRaDec,
    GetVersion,
    LocalProtocolError,
    Location,
    MalformedReply,
    Model,
    PassthroughFailed,
    Position,
    SetTrackingMode,
    SynScanClientConnection,
    SynScanServerConnection,
    UnexpectedData,
    Version,
    VersionDialect,
)


def state_of(client: SynScanClientConnection) -> ClientState:
    """The state, read through a call so that mypy does not keep an earlier narrowing."""
    return client.state


def feed_bytewise(client: SynScanClientConnection, data: bytes) -> list[object]:
    events: list[object] = []
    for byte in data:
        client.receive_data(bytes((byte,)))
        while (event := client.next_event()) is not NEED_DATA:
            events.append(event)
    return events


def exchange(
    client: SynScanClientConnection,
    server: SynScanServerConnection,
    command: AnyCommand,
    reply: AnyReply,
) -> object:
    server.receive_data(client.send(command))
    assert server.next_event() == command
    client.receive_data(server.send(reply))
    return client.next_event()


def test_client_and_server_talk() -> None:
    client, server = SynScanClientConnection(), SynScanServerConnection()
    assert exchange(client, server, Echo(ord("x")), EchoReply(ord("x"))) == EchoReply(ord("x"))
    position = Position.from_ra_dec(5.5, -20.0)
    assert exchange(client, server, GetRaDec(), position) == position
    location = Location(35, 35, 35, True, 35, 35, 35, False)
    assert exchange(client, server, GetLocation(), location) == location
    assert state_of(client) is ClientState.IDLE
    assert server.unanswered == ()


def test_reply_is_incremental_and_waits_for_its_length() -> None:
    client = SynScanClientConnection()
    client.send(GetLocation())
    wire = bytes((35, 35, 35, 0, 35, 35, 35, 0)) + b"#"
    client.receive_data(wire[:-1])
    assert client.next_event() is NEED_DATA
    assert state_of(client) is ClientState.AWAITING_REPLY
    client.receive_data(wire[-1:])
    assert client.next_event() == Location(35, 35, 35, False, 35, 35, 35, False)


def test_version_dialect_is_decided_as_bytes_arrive() -> None:
    client = SynScanClientConnection()
    client.send(GetVersion())
    assert feed_bytewise(client, b"\x04\x15#") == [
        Version(4, 21, None, VersionDialect.NEXSTAR_BINARY)
    ]
    client.send(GetVersion())
    assert feed_bytewise(client, b"\x03\x27\x01#") == [
        Version(3, 39, 1, VersionDialect.SYNSCAN_BINARY)
    ]
    client.send(GetVersion())
    assert feed_bytewise(client, b"042507#") == [Version(4, 37, 7)]


def test_swapped_model_reply() -> None:
    client = SynScanClientConnection()
    client.send(GetModel())
    assert feed_bytewise(client, b"#\x00") == [Model(0, swapped=True)]


def test_sending_while_a_command_is_in_flight_is_a_local_error() -> None:
    client = SynScanClientConnection()
    client.send(GetRaDec())
    with pytest.raises(LocalProtocolError, match="awaiting reply"):
        client.send(CancelGoto())
    assert client.in_flight == GetRaDec()


def test_malformed_reply_then_reset_and_resync_with_echo() -> None:
    client = SynScanClientConnection()
    client.send(GetRaDec(precise=False))
    client.receive_data(b"34AB;12")
    event = client.next_event()
    assert isinstance(event, MalformedReply)
    assert (event.data, event.index) == (b"34AB;", 4)
    assert state_of(client) is ClientState.ERROR
    with pytest.raises(LocalProtocolError, match="reset"):
        client.send(Echo(0x55))
    assert client.reset() == b"12"
    # the rest of the late reply arrives after the echo was sent: it is drained, not an error
    client.send(Echo(0x55))
    events = feed_bytewise(client, b"CE#" + b"\x55#")
    assert events == [
        UnexpectedData(b"C"),
        UnexpectedData(b"E"),
        UnexpectedData(b"#"),
        EchoReply(0x55),
    ]
    assert state_of(client) is ClientState.IDLE
    # resynchronised: a wrong echo is an error again
    client.send(Echo(0x56))
    client.receive_data(b"x#")
    assert isinstance(client.next_event(), MalformedReply)


def test_reset_after_timeout_forgets_the_command() -> None:
    client = SynScanClientConnection()
    client.send(GetRaDec())
    assert client.reset() == b""
    assert client.in_flight is None
    client.send(Echo(ord("a")))
    client.receive_data(b"12AB0500,4000")  # late reply to the forgotten command
    client.receive_data(b"0500#a#")
    events = []
    while (event := client.next_event()) is not NEED_DATA:
        events.append(event)
    assert events == [UnexpectedData(b"12AB0500,40000500#"), EchoReply(ord("a"))]


def test_bytes_without_a_command_in_flight_are_unexpected() -> None:
    client = SynScanClientConnection()
    client.receive_data(b"#")
    assert client.next_event() == UnexpectedData(b"#")
    assert client.next_event() is NEED_DATA


def test_bytes_received_before_a_send_are_not_its_reply() -> None:
    client = SynScanClientConnection()
    client.receive_data(b"\x05")
    client.send(GetModel())
    client.receive_data(b"\x06#")
    assert client.next_event() == UnexpectedData(b"\x05")
    assert client.next_event() == Model(6)


def test_failed_passthrough_is_a_reply_not_an_error() -> None:
    client = SynScanClientConnection()
    client.send(FixedRateSlew(Axis.AZM_RA, True, 4))
    assert feed_bytewise(client, b"\x02#") == [PassthroughFailed(b"", 2)]
    assert state_of(client) is ClientState.IDLE


def test_server_answers_back_to_back_commands_in_order() -> None:
    server = SynScanServerConnection()
    server.receive_data(b"T\x00MM")
    events = [server.next_event() for _ in range(4)]
    assert events == [SetTrackingMode(0), CancelGoto(), CancelGoto(), NEED_DATA]
    assert len(server.unanswered) == 3
    assert server.send(Ack()) + server.send(Ack()) + server.send(Ack()) == b"###"
    with pytest.raises(LocalProtocolError, match="no command"):
        server.send(Ack())


def test_server_refuses_a_reply_that_cannot_answer_the_command() -> None:
    server = SynScanServerConnection()
    server.receive_data(b"e")
    assert server.next_event() == GetRaDec()
    with pytest.raises(LocalProtocolError, match="cannot answer"):
        server.send(Position(Frame.HORIZONTAL, 0, 0))
    with pytest.raises(LocalProtocolError, match="cannot answer"):
        server.send(Position(Frame.EQUATORIAL, 0, 0, precise=False))
    assert server.skip_reply() == GetRaDec()
    assert server.unanswered == ()
    with pytest.raises(LocalProtocolError):
        server.skip_reply()


def test_server_refuses_an_echo_of_another_byte() -> None:
    server = SynScanServerConnection()
    server.receive_data(b"Ka")
    assert server.next_event() == Echo(ord("a"))
    with pytest.raises(LocalProtocolError):
        server.send(EchoReply(ord("b")))
    assert server.send(EchoReply(ord("a"))) == b"a#"


def test_server_discard_partial() -> None:
    server = SynScanServerConnection()
    server.receive_data(b"r1234")
    assert server.next_event() is NEED_DATA
    assert server.discard_partial() == b"r1234"
    assert server.parser.offset == 5
    assert server.unanswered == ()


def test_a_polls_reply_in_the_same_bytes_as_last_time_is_the_same_reply_object() -> None:
    client = SynScanClientConnection()
    replies = []
    for data in (b"12AB0500,34CD0500#", b"12AB0500,34CD0500#", b"12AC0500,34CD0500#"):
        client.send(GetRaDec())
        client.receive_data(data[:9])
        assert client.next_event() is NEED_DATA  # a partial reply is never the remembered one
        replies.append(client.receive_and_next_event(data[9:]))
        assert client.state is ClientState.IDLE
    assert replies[0] is replies[1]
    assert replies[2] == Position(Frame.EQUATORIAL, 0x12AC0500, 0x34CD0500)
    assert replies[0] == Position(Frame.EQUATORIAL, 0x12AB0500, 0x34CD0500)
    # The standard-precision poll is another command: its bytes never meet the precise reply's.
    client.send(GetRaDec(precise=False))
    assert client.receive_and_next_event(b"12AB,34CD#") == Position(
        Frame.EQUATORIAL, 0x12AB, 0x34CD, precise=False
    )
    # A wrong reply after a remembered one is still malformed, not taken for it.
    client.send(GetRaDec())
    event = client.receive_and_next_event(b"12AB0500;34CD0500#")
    assert isinstance(event, MalformedReply)
    # Commands whose replies are not polls are parsed every time.
    client.reset()
    versions = []
    for _ in range(2):
        client.send(GetVersion())
        versions.append(client.receive_and_next_event(b"\x04\x0e\x05#"))
    assert versions[0] == versions[1]
    assert versions[0] is not versions[1]
    assert GetRaDec.repeats_reply
    assert not GetVersion.repeats_reply
