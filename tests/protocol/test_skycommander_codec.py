"""Sky Commander commands, coordinate text, and both state machines (device server, PC client)."""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.protocol.skytracker import (
    MAX_LINE_LENGTH,
    NEED_DATA,
    Acknowledge,
    BadReply,
    CommanderClient,
    CommanderCommand,
    CommanderServer,
    CoordinateRangeError,
    IncompleteFrame,
    LineTooLong,
    LoadObject,
    LocalProtocolError,
    MalformedCommand,
    OffsetsReply,
    PositionReply,
    RatesReply,
    ReadOffsets,
    ReadPosition,
    ReadRates,
    Realign,
    Reply,
    UnknownCommand,
)
from scopelink.protocol.skytracker.coordinates import format_dec_degrees, format_ra_hours
from tests.support.skytracker_codec import calfloat_values, chunk_cuts, drain, feed, wire_length

ra_on_grid = st.integers(0, 23999).map(lambda n: n / 1000)
dec_on_grid = st.integers(-90000, 90000).map(lambda n: n / 1000)
slots = st.sampled_from([*range(59), 99])

commander_commands: st.SearchStrategy[CommanderCommand] = st.one_of(
    st.sampled_from([ReadPosition(), Realign(), ReadOffsets(), ReadRates()]),
    st.builds(LoadObject, slots, ra_on_grid, dec_on_grid),
)

replies_by_command: dict[type[Reply], st.SearchStrategy[Reply]] = {
    PositionReply: st.builds(PositionReply, ra_on_grid, dec_on_grid),
    Acknowledge: st.just(Acknowledge()),
    OffsetsReply: st.builds(OffsetsReply, calfloat_values, calfloat_values),
    RatesReply: st.builds(RatesReply, calfloat_values, calfloat_values),
}


# --- wire examples -------------------------------------------------------------------------


def test_position_reply_is_the_sixteen_bytes_indi_reads() -> None:
    reply = PositionReply(12.345, 67.89)
    assert reply.encode() == b" 12.345 +67.890\x00"
    assert PositionReply.size == 16
    assert str(reply) == "position RA 12h 20m 42s, Dec +67.890°"
    assert PositionReply(3.5, -5.25).encode() == b" 03.500 -05.250\x00"


@pytest.mark.parametrize(
    ("wire", "ra", "dec"),
    [
        (b" 12.345 +67.890\x00", 12.345, 67.89),
        (b"  1.5 -5.25\x00\x00\x00\x00\x00", 1.5, -5.25),
        (b" 24.000 +00.000\x00", 0.0, 0.0),
        (b" 06.000 45.0000 ", 6.0, 45.0),
    ],
)
def test_position_reply_parsing_is_lenient_like_scanf(wire: bytes, ra: float, dec: float) -> None:
    assert PositionReply.decode(wire) == PositionReply(ra, dec)


@pytest.mark.parametrize(
    "wire",
    [
        b" 25.000 +00.000\x00",
        b" 12.000 +91.000\x00",
        b" 12.000\x00+45.000\x00",
        b"ABCDEFGHIJKLMNOP",
    ],
)
def test_position_reply_garbage_is_a_bad_reply(wire: bytes) -> None:
    client = CommanderClient()
    client.send(ReadPosition())
    client.receive_data(wire)
    (event,) = drain(client)
    assert isinstance(event, BadReply)
    assert event.data == wire


def test_load_object_lines() -> None:
    assert LoadObject.current(12.345, 67.89).encode() == b"L99 12.345 +67.890\r"
    assert LoadObject(7, 0.5, -0.25).encode() == b"L07 00.500 -00.250\r"
    assert "slot 7" in LoadObject(7, 0.5, -0.25).describe()
    assert "current object" in LoadObject.current(1.0, 2.0).describe()


@pytest.mark.parametrize(
    ("ra", "text"),
    [
        (23.9996, "00.000"),
        (23.9994, "23.999"),
        (0.0, "00.000"),
        (12.3456, "12.346"),
        (12.3455, "12.345"),
    ],
)
def test_ra_rounds_to_three_decimals_and_wraps_at_24h(ra: float, text: str) -> None:
    # 12.3455 is stored as 12.34549999...: rounding is of the exact binary value.
    assert format_ra_hours(ra) == text


@pytest.mark.parametrize(
    ("dec", "text"),
    [(-0.0004, "+00.000"), (89.9996, "+90.000"), (-90.0, "-90.000"), (5.0, "+05.000")],
)
def test_dec_is_always_signed_with_three_decimals(dec: float, text: str) -> None:
    assert format_dec_degrees(dec) == text


@pytest.mark.parametrize(
    ("ra", "dec"), [(24.0, 0.0), (-0.001, 0.0), (math.nan, 0.0), (1.0, 90.001), (1.0, -math.inf)]
)
def test_out_of_range_coordinates_are_refused(ra: float, dec: float) -> None:
    with pytest.raises(CoordinateRangeError):
        LoadObject.current(ra, dec)
    with pytest.raises(CoordinateRangeError):
        PositionReply(ra, dec)


def test_slots_are_00_to_58_or_99() -> None:
    with pytest.raises(ValueError, match="00-58 or 99"):
        LoadObject(59, 1.0, 1.0)


def test_offsets_and_rates_are_two_floats_altitude_first() -> None:
    assert OffsetsReply(1.0, -1.0).encode() == bytes.fromhex("40800000 C0800000")
    assert RatesReply.decode(bytes.fromhex("40000000 00000000")) == RatesReply(0.5, 0.0)
    assert "°/min" in RatesReply(0.25, 0.0).describe()
    assert "counter-clockwise" in OffsetsReply(0.0, 2.0).describe()


# --- server behaviour ----------------------------------------------------------------------


def test_server_frames_lines_by_cr_and_single_bytes_alone() -> None:
    server = CommanderServer()
    server.receive_data(b"\rL99 12.3")
    assert drain(server) == [ReadPosition()]
    server.receive_data(b"45 +67.890\rNOR")
    assert drain(server) == [
        LoadObject.current(12.345, 67.89),
        Realign(),
        ReadOffsets(),
        ReadRates(),
    ]


def test_server_accepts_loose_but_sane_lines() -> None:
    server = CommanderServer()
    server.receive_data(b"L05  1.5  -2\r")
    assert drain(server) == [LoadObject(5, 1.5, -2.0)]


@pytest.mark.parametrize(
    "line", [b"L60 12.345 +67.890\r", b"L99 25.000 +00.000\r", b"L99 12.345\r", b"Lxx\r"]
)
def test_malformed_lines_are_errors_and_parsing_continues(line: bytes) -> None:
    server = CommanderServer()
    server.receive_data(line + b"O")
    events = drain(server)
    assert isinstance(events[0], MalformedCommand)
    assert events[0].data == line
    assert events[1:] == [ReadOffsets()]


def test_over_long_line_is_an_error_and_the_parser_resynchronises_at_the_next_cr() -> None:
    server = CommanderServer()
    junk = b"L" + b"9" * 40
    server.receive_data(junk + b"\rO")
    events = drain(server)
    assert [type(e) for e in events] == [LineTooLong, LineTooLong, ReadOffsets]
    assert events[0].offset == 0
    assert len(events[0].data) == MAX_LINE_LENGTH
    assert events[1].offset == MAX_LINE_LENGTH
    assert events[1].data.endswith(b"\r")


def test_garbage_never_makes_the_server_wait_beyond_the_line_bound() -> None:
    server = CommanderServer()
    server.receive_data(b"L" * (5 * MAX_LINE_LENGTH))
    events = drain(server)
    assert sum(len(e.data) for e in events) == 5 * MAX_LINE_LENGTH
    assert server.buffered == b""


def test_unknown_bytes_are_reported_one_by_one() -> None:
    server = CommanderServer()
    server.receive_data(b"\nxR")
    assert drain(server) == [
        UnknownCommand(0, b"\n", "not a Sky Commander command"),
        UnknownCommand(1, b"x", "not a Sky Commander command"),
        ReadRates(),
    ]


def test_discard_partial_drops_an_unfinished_line() -> None:
    server = CommanderServer()
    server.receive_data(b"OL99 12")
    assert drain(server) == [ReadOffsets()]
    assert server.next_event() is NEED_DATA
    dropped = server.discard_partial()
    assert dropped == IncompleteFrame(1, b"L99 12", "unfinished line dropped after a pause")
    assert server.discard_partial() is None
    server.receive_data(b"\r")
    assert drain(server) == [ReadPosition()]


# --- client behaviour ----------------------------------------------------------------------


def test_client_reads_replies_by_length() -> None:
    client = CommanderClient()
    assert client.send(ReadOffsets()) == b"O"
    client.receive_data(bytes.fromhex("40800000 C080"))
    assert client.next_event() is NEED_DATA
    client.receive_data(bytes.fromhex("0000"))
    assert drain(client) == [OffsetsReply(1.0, -1.0)]


def test_realign_expects_no_reply() -> None:
    client = CommanderClient()
    assert client.send(Realign()) == b"N"
    assert client.awaiting is None
    assert client.send(ReadRates()) == b"R"


def test_client_sends_one_command_at_a_time() -> None:
    client = CommanderClient()
    client.send(ReadPosition())
    with pytest.raises(LocalProtocolError, match="still waiting"):
        client.send(ReadPosition())


def test_load_object_reply_other_than_a_is_bad() -> None:
    client = CommanderClient()
    client.send(LoadObject.current(1.0, 2.0))
    client.receive_data(b"?")
    (event,) = drain(client)
    assert isinstance(event, BadReply)
    assert "acknowledge" in event.reason


# --- properties ----------------------------------------------------------------------------


@given(commander_commands)
def test_commands_round_trip_client_to_server(command: CommanderCommand) -> None:
    client, server = CommanderClient(), CommanderServer()
    wire = client.send(command)
    server.receive_data(wire)
    assert drain(server) == [command]
    assert server.offset == len(wire)
    assert str(command) == command.describe()


@given(st.data())
def test_replies_round_trip_server_to_client(data: st.DataObject) -> None:
    command = data.draw(commander_commands.filter(lambda c: c.reply is not None))
    assert command.reply is not None
    reply = data.draw(replies_by_command[command.reply])
    client = CommanderClient()
    client.send(command)
    wire = CommanderServer().send(reply)
    assert len(wire) == command.reply.size
    assert feed(client, wire, range(len(wire))) == [reply]  # one byte at a time


@given(st.integers(0, 99), st.floats(0, 24, exclude_max=True), st.floats(-90, 90))
def test_encoding_any_load_object_is_stable_after_one_trip(
    slot: int, ra: float, dec: float
) -> None:
    if slot not in (*range(59), 99):
        return
    once = LoadObject(slot, ra, dec).encode()
    assert LoadObject.decode(once).encode() == once
    assert len(once) == 19


@given(st.lists(commander_commands, max_size=10), st.data())
def test_server_parsing_is_the_same_for_any_chunking(
    commands: list[CommanderCommand], data: st.DataObject
) -> None:
    wire = b"".join(command.encode() for command in commands)
    assert feed(CommanderServer(), wire, data.draw(chunk_cuts(len(wire)))) == commands
    assert feed(CommanderServer(), wire, range(len(wire))) == commands


garbage = st.binary(max_size=120) | st.lists(
    st.sampled_from(b"L\rNOR 0123456789.+-\x00Qq"), max_size=120
).map(bytes)


def _server_run(wire: bytes, cuts: Any) -> tuple[list[Any], CommanderServer]:
    server = CommanderServer()
    return feed(server, wire, cuts), server


@settings(max_examples=150)
@given(garbage, st.data())
def test_server_survives_garbage_and_accounts_for_every_byte(
    wire: bytes, data: st.DataObject
) -> None:
    whole, server = _server_run(wire, ())
    chunked, _ = _server_run(wire, data.draw(chunk_cuts(len(wire))))
    one_by_one, _ = _server_run(wire, range(len(wire)))
    assert whole == chunked == one_by_one
    position = 0
    for event in whole:
        if hasattr(event, "offset"):
            assert event.offset == position
            assert wire[position : position + len(event.data)] == event.data
        position += len(event.data) if hasattr(event, "data") else len(event.encode())
    assert position == server.offset
    assert len(server.buffered) < MAX_LINE_LENGTH
    assert server.offset + len(server.buffered) == len(wire)


@settings(max_examples=150)
@given(garbage, st.data())
def test_client_survives_garbage_for_any_pending_command(wire: bytes, data: st.DataObject) -> None:
    command = data.draw(commander_commands)
    cuts = data.draw(chunk_cuts(len(wire)))
    runs = []
    for split in ((), cuts, range(len(wire))):
        client = CommanderClient()
        client.send(command)
        events = feed(client, wire, split)
        assert sum(wire_length(e) for e in events) == client.offset
        assert client.offset + len(client.buffered) == len(wire)
        runs.append(events)
    assert runs[0] == runs[1] == runs[2]
