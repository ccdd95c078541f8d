"""The Stellarium binary codec: wire units, known bytes, round trips, chunking and garbage."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.protocol.stellarium import (
    MAX_MESSAGE_LENGTH,
    NEED_DATA,
    BadLength,
    CurrentPosition,
    GotoMessage,
    SkippedMessage,
    StellariumClientConnection,
    StellariumServerConnection,
    dec_from_wire,
    dec_to_wire,
    ra_from_wire,
    ra_to_wire,
)

gotos = st.builds(
    GotoMessage,
    st.integers(0, 2**32 - 1),
    st.integers(-(2**30), 2**30),
    st.integers(-(2**63), 2**63 - 1),
)
positions = st.builds(
    CurrentPosition,
    st.integers(0, 2**32 - 1),
    st.integers(-(2**30), 2**30),
    st.integers(-(2**63), 2**63 - 1),
    st.integers(-(2**31), 2**31 - 1),
)


def drain(connection: StellariumServerConnection) -> list[object]:
    events: list[object] = []
    while (event := connection.next_event()) is not NEED_DATA:
        events.append(event)
    return events


def test_wire_units_match_the_protocol_text() -> None:
    assert ra_to_wire(12.0) == 0x80000000
    assert ra_to_wire(24.0) == 0
    assert ra_to_wire(6.0) == 0x40000000
    assert dec_to_wire(90.0) == 0x40000000
    assert dec_to_wire(-90.0) == -0x40000000
    assert ra_from_wire(0xC0000000) == 18.0
    assert dec_from_wire(-0x20000000) == -45.0
    with pytest.raises(ValueError, match="declination"):
        dec_to_wire(90.5)


def test_a_goto_as_stellarium_sends_it() -> None:
    # LENGTH 20, TYPE 0, TIME, RA 12 h, DEC +45°: all little-endian.
    frame = struct.pack("<HHqIi", 20, 0, 1_700_000_000_000_000, 0x80000000, 0x20000000)
    connection = StellariumServerConnection()
    connection.receive_data(frame)
    event = connection.next_event()
    assert isinstance(event, GotoMessage)
    assert event.ra_hours == 12.0
    assert event.dec_deg == 45.0
    assert event.client_time_us == 1_700_000_000_000_000
    assert event.encode() == frame


def test_a_position_is_24_bytes_with_status() -> None:
    data = CurrentPosition.from_degrees(18.0, -45.0, 5, -1).encode()
    assert data == struct.pack("<HHqIii", 24, 0, 5, 0xC0000000, -0x20000000, -1)


@given(gotos)
def test_goto_round_trip(goto: GotoMessage) -> None:
    server = StellariumServerConnection()
    server.receive_data(StellariumClientConnection().send(goto))
    assert server.next_event() == goto
    assert server.next_event() is NEED_DATA


@given(positions)
def test_position_round_trip(position: CurrentPosition) -> None:
    client = StellariumClientConnection()
    client.receive_data(StellariumServerConnection().send(position))
    assert client.next_event() == position
    assert client.next_event() is NEED_DATA


@given(st.lists(gotos, max_size=5), st.data())
def test_chunking_does_not_change_the_events(
    gotos_sent: list[GotoMessage], data: st.DataObject
) -> None:
    stream = b"".join(goto.encode() for goto in gotos_sent)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=10)))
    connection = StellariumServerConnection()
    events: list[object] = []
    start = 0
    for cut in [*cuts, len(stream)]:
        connection.receive_data(stream[start:cut])
        start = cut
        events += drain(connection)
    assert events == gotos_sent


def test_unknown_types_and_wrong_lengths_are_skipped_whole() -> None:
    good = GotoMessage.from_degrees(1.0, 2.0)
    unknown = struct.pack("<HH", 8, 7) + b"abcd"
    short_goto = struct.pack("<HH", 12, 0) + bytes(8)
    connection = StellariumServerConnection()
    connection.receive_data(unknown + short_goto + good.encode())
    first, second, third = drain(connection)
    assert isinstance(first, SkippedMessage)
    assert first.message_type == 7
    assert "unknown" in first.describe()
    assert isinstance(second, SkippedMessage)
    assert "20 bytes" in second.reason
    assert third == good


@pytest.mark.parametrize("length", [0, 3, MAX_MESSAGE_LENGTH + 1, 0xFFFF])
def test_an_impossible_length_breaks_the_connection(length: int) -> None:
    connection = StellariumServerConnection()
    connection.receive_data(struct.pack("<HH", length, 0) + bytes(40))
    event = connection.next_event()
    assert isinstance(event, BadLength)
    assert event.length == length
    assert "cannot be framed" in event.describe()
    assert connection.broken
    connection.receive_data(GotoMessage(0, 0).encode())
    assert connection.next_event() is NEED_DATA


@given(st.binary(max_size=400))
def test_garbage_never_raises(garbage: bytes) -> None:
    for connection in (StellariumServerConnection(), StellariumClientConnection()):
        connection.receive_data(garbage)
        for _ in range(len(garbage) + 2):
            event = connection.next_event()
            if event is NEED_DATA:
                break
            assert isinstance(event, GotoMessage | CurrentPosition | SkippedMessage | BadLength)
