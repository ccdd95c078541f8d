"""Property-based tests of the SynScan codec: round trips, incremental parsing, garbage."""

from __future__ import annotations

import itertools
from collections.abc import Iterable

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scopelink.protocol.synscan import (
    NEED_DATA,
    Ack,
    Aligned,
    AnyCommand,
    AnyReply,
    Axis,
    CancelGoto,
    CommandParser,
    DateTime,
    DeviceVersion,
    Echo,
    EchoReply,
    FixedRateSlew,
    Frame,
    GetAzAlt,
    GetDeviceVersion,
    GetLocation,
    GetModel,
    GetPointingState,
    GetRaDec,
    GetTime,
    GetTrackingMode,
    GetVersion,
    GotoAzAlt,
    GotoInProgress,
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    Location,
    MalformedCommand,
    MalformedReply,
    Model,
    ParsedCommand,
    Passthrough,
    PassthroughFailed,
    PassthroughReply,
    PointingSide,
    PointingState,
    Position,
    SetAxisPosition,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SlowGoto,
    SyncRaDec,
    SynScanClientConnection,
    TrackingModeReply,
    UnexpectedData,
    UnknownCommand,
    VariableRateSlew,
    Version,
    VersionDialect,
    angles,
    encode_command,
    encode_reply,
    parse_reply,
    passthrough_command,
    reply_shape,
)

HASH = 0x23
FAST = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

bytes_ = st.integers(0, 255)
axes = st.sampled_from(Axis)


def units(precise: bool) -> st.SearchStrategy[int]:
    return st.integers(0, angles.units_per_revolution(precise) - 1)


def pairs(cls: type[GotoRaDec | SyncRaDec | GotoAzAlt]) -> st.SearchStrategy[AnyCommand]:
    return st.booleans().flatmap(
        lambda precise: st.builds(cls, units(precise), units(precise), st.just(precise))
    )


locations = st.builds(
    Location, bytes_, bytes_, bytes_, st.booleans(), bytes_, bytes_, bytes_, st.booleans()
)
date_times = st.builds(
    DateTime,
    bytes_,
    bytes_,
    bytes_,
    bytes_,
    bytes_,
    st.integers(2000, 2255),
    st.integers(-128, 127),
    st.booleans(),
)
position24 = st.integers(0, angles.POSITION24_UNITS - 1)
passthrough_commands = st.one_of(
    st.builds(VariableRateSlew, axes, st.booleans(), st.integers(0, angles.MAX_RATE_UNITS)),
    st.builds(FixedRateSlew, axes, st.booleans(), st.integers(0, 9)),
    st.builds(GetDeviceVersion, axes),
    st.builds(SlowGoto, axes, position24),
    st.builds(SetAxisPosition, axes, position24),
    st.binary(min_size=7, max_size=7).map(passthrough_command),
)
commands: st.SearchStrategy[AnyCommand] = st.one_of(
    st.builds(GetRaDec, st.booleans()),
    st.builds(GetAzAlt, st.booleans()),
    pairs(GotoRaDec),
    pairs(SyncRaDec),
    pairs(GotoAzAlt),
    st.just(GetTrackingMode()),
    st.builds(SetTrackingMode, bytes_),
    passthrough_commands,
    st.just(GetLocation()),
    st.builds(SetLocation, locations),
    st.just(GetTime()),
    st.builds(SetTime, date_times),
    st.just(GetVersion()),
    st.just(GetModel()),
    st.builds(Echo, bytes_),
    st.just(IsAligned()),
    st.just(IsGotoInProgress()),
    st.just(CancelGoto()),
    st.just(GetPointingState()),
)

binary_majors = bytes_.filter(lambda b: not angles.is_hex_digit(b))
versions = st.one_of(
    st.builds(Version, bytes_, bytes_, bytes_, st.just(VersionDialect.SYNSCAN_HEX)),
    st.builds(Version, binary_majors, bytes_, st.none(), st.just(VersionDialect.NEXSTAR_BINARY)),
    st.builds(
        Version,
        binary_majors,
        bytes_,
        bytes_.filter(lambda b: b != HASH),
        st.just(VersionDialect.SYNSCAN_BINARY),
    ),
)
models = st.one_of(
    st.builds(Model, bytes_, st.just(False)),
    st.builds(Model, bytes_.filter(lambda b: b != HASH), st.just(True)),
)


def replies_for(command: AnyCommand) -> st.SearchStrategy[AnyReply]:
    """Every reply the hand control may give to ``command``."""
    match command:
        case GetRaDec(precise) | GetAzAlt(precise):
            frame = Frame.EQUATORIAL if isinstance(command, GetRaDec) else Frame.HORIZONTAL
            return st.builds(
                Position, st.just(frame), units(precise), units(precise), st.just(precise)
            )
        case GetTrackingMode():
            return st.builds(TrackingModeReply, bytes_)
        case GetLocation():
            return locations
        case GetTime():
            return date_times
        case GetVersion():
            return versions
        case GetModel():
            return models
        case Echo(value):
            return st.just(EchoReply(value))
        case IsAligned():
            return st.builds(Aligned, st.booleans())
        case IsGotoInProgress():
            return st.builds(GotoInProgress, st.booleans())
        case GetPointingState():
            return st.builds(PointingState, st.sampled_from(PointingSide))
        case (
            VariableRateSlew()
            | FixedRateSlew()
            | GetDeviceVersion()
            | SlowGoto()
            | SetAxisPosition()
            | Passthrough()
        ):
            count = reply_shape(command).lengths[0] - 1
            failed = st.builds(
                PassthroughFailed,
                st.binary(min_size=count, max_size=count),
                bytes_.filter(lambda b: b != HASH),
            )
            if isinstance(command, GetDeviceVersion):
                return st.one_of(st.builds(DeviceVersion, bytes_, bytes_), failed)
            if isinstance(command, Passthrough):
                return st.one_of(
                    st.binary(min_size=count, max_size=count).map(PassthroughReply), failed
                )
            return st.one_of(st.just(Ack()), failed)
        case _:
            return st.just(Ack())


exchanges = commands.flatmap(lambda command: st.tuples(st.just(command), replies_for(command)))


def chunked(data: bytes, cuts: Iterable[int]) -> list[bytes]:
    points = sorted({cut % (len(data) + 1) for cut in cuts} | {0, len(data)})
    return [data[start:end] for start, end in itertools.pairwise(points)]


def server_frames(chunks: Iterable[bytes]) -> tuple[list[object], bytes]:
    parser = CommandParser()
    events: list[object] = []
    for chunk in chunks:
        parser.receive_data(chunk)
        while (event := parser.next_frame()) is not NEED_DATA:
            events.append(event)
            assert len(events) <= parser.offset, "every event consumes at least one byte"
    return events, parser.discard_partial()


def merge_unexpected(events: list[object]) -> list[object]:
    """Adjacent `UnexpectedData` events joined: their boundaries follow the reads, nothing else."""
    merged: list[object] = []
    for event in events:
        if isinstance(event, UnexpectedData) and merged and isinstance(merged[-1], UnexpectedData):
            merged[-1] = UnexpectedData(merged[-1].data + event.data)
        else:
            merged.append(event)
    return merged


# ------------------------------------------------------------------------------------- round trips


@FAST
@given(commands)
def test_every_command_round_trips_through_the_server_parser(command: AnyCommand) -> None:
    wire = encode_command(command)
    events, pending = server_frames([wire])
    assert events == [ParsedCommand(command, wire, 0)]
    assert pending == b""
    assert str(command)


@FAST
@given(exchanges)
def test_every_reply_round_trips_through_the_client(exchange: tuple[AnyCommand, AnyReply]) -> None:
    command, reply = exchange
    wire = encode_reply(reply)
    assert len(wire) in reply_shape(command).lengths
    assert parse_reply(command, wire) == reply
    client = SynScanClientConnection()
    assert client.send(command) == encode_command(command)
    client.receive_data(wire)
    assert client.next_event() == reply
    assert client.next_event() is NEED_DATA
    assert str(reply)


@FAST
@given(exchanges, st.lists(st.integers(0, 64), max_size=6))
def test_replies_parse_the_same_in_any_chunking(
    exchange: tuple[AnyCommand, AnyReply], cuts: list[int]
) -> None:
    command, reply = exchange
    wire = encode_reply(reply)
    for chunks in (chunked(wire, cuts), [bytes((b,)) for b in wire]):
        client = SynScanClientConnection()
        client.send(command)
        events = []
        for chunk in chunks:
            client.receive_data(chunk)
            while (event := client.next_event()) is not NEED_DATA:
                events.append(event)
        assert events == [reply]


@FAST
@given(st.lists(commands, max_size=8), st.lists(st.integers(0, 3), min_size=9, max_size=9))
def test_back_to_back_commands_with_stray_hashes(
    commands_: list[AnyCommand], hashes: list[int]
) -> None:
    wire = b"".join(
        b"#" * count + encode_command(c) for count, c in zip(hashes, commands_, strict=False)
    )
    wire += b"#" * hashes[-1]
    events, pending = server_frames([wire])
    assert [e.command for e in events if isinstance(e, ParsedCommand)] == commands_
    assert len(events) == len(commands_)
    assert pending == b""


@FAST
@given(pairs(GotoRaDec) | pairs(SyncRaDec) | pairs(GotoAzAlt))
def test_lowercase_hex_commands_are_accepted(command: AnyCommand) -> None:
    wire = encode_command(command)
    events, _ = server_frames([wire[:1] + wire[1:].lower()])
    assert [e.command for e in events if isinstance(e, ParsedCommand)] == [command]


@FAST
@given(st.booleans(), st.booleans().flatmap(lambda p: st.tuples(st.just(p), units(p), units(p))))
def test_lowercase_hex_positions_are_accepted(
    equatorial: bool, reply_units: tuple[bool, int, int]
) -> None:
    precise, first, second = reply_units
    command: AnyCommand = GetRaDec(precise) if equatorial else GetAzAlt(precise)
    frame = Frame.EQUATORIAL if equatorial else Frame.HORIZONTAL
    reply = Position(frame, first, second, precise)
    assert parse_reply(command, encode_reply(reply).lower()) == reply


@FAST
@given(st.floats(-720, 720, allow_nan=False), st.booleans())
def test_degrees_round_trip_within_one_step(degrees: float, precise: bool) -> None:
    units_ = angles.degrees_to_units(degrees, precise)
    back = angles.units_to_degrees(units_, precise)
    step = 360.0 / (angles.POSITION24_UNITS if precise else angles.STANDARD_UNITS)
    difference = (back - degrees) % 360.0
    assert min(difference, 360.0 - difference) <= step / 2 + 1e-9


@FAST
@given(st.floats(-90, 90, allow_nan=False), st.floats(-180, 180, allow_nan=False))
def test_location_from_degrees_is_within_half_an_arcsecond(
    latitude: float, longitude: float
) -> None:
    location = Location.from_degrees(latitude, longitude)
    assert abs(location.latitude - latitude) <= 0.5 / 3600 + 1e-9
    difference = (location.longitude - longitude + 180.0) % 360.0 - 180.0
    assert abs(difference) <= 0.5 / 3600 + 1e-9


# ----------------------------------------------------------------------------------------- garbage


@FAST
@given(st.binary(max_size=200), st.lists(st.integers(0, 250), max_size=8))
def test_server_parser_accounts_for_every_garbage_byte(data: bytes, cuts: list[int]) -> None:
    whole, whole_pending = server_frames([data])
    by_byte, byte_pending = server_frames([bytes((b,)) for b in data])
    by_chunk, chunk_pending = server_frames(chunked(data, cuts))
    assert whole == by_byte == by_chunk
    assert whole_pending == byte_pending == chunk_pending
    position = 0
    for event in whole:
        match event:
            case ParsedCommand(_, raw, offset) | MalformedCommand(raw, _, offset, _):
                length = len(raw)
            case UnknownCommand(byte, offset):
                raw, length = bytes((byte,)), 1
            case _:
                raise AssertionError(f"unexpected event {event!r}")
        assert set(data[position:offset]) <= {HASH}, "only stray '#' are skipped silently"
        assert data[offset : offset + length] == raw
        position = offset + length
    assert set(data[position : len(data) - len(whole_pending)]) <= {HASH}
    assert data.endswith(whole_pending)


def drive_client(commands_: list[AnyCommand], chunks: Iterable[bytes]) -> tuple[list[object], int]:
    """Send commands one after another as replies come in; reset after errors. Returns events and
    the number of bytes accounted for (consumed by replies, reported, or dropped by reset)."""
    client = SynScanClientConnection()
    queue = list(commands_)
    client.send(queue.pop(0))
    events: list[object] = []
    accounted = 0
    for chunk in chunks:
        client.receive_data(chunk)
        while (event := client.next_event()) is not NEED_DATA:
            events.append(event)
            match event:
                case MalformedReply(_, data, _, _) | UnexpectedData(data):
                    accounted += len(data)
                case _:
                    accounted += len(encode_reply(event))
            if isinstance(event, MalformedReply) and (dropped := client.reset()):
                # bytes already buffered when reset() drops them: reported like later arrivals
                events.append(UnexpectedData(dropped))
                accounted += len(dropped)
            if client.in_flight is None and queue:
                client.send(queue.pop(0))
    accounted += len(client.reset())
    return events, accounted


@FAST
@given(
    st.lists(commands, min_size=1, max_size=6),
    st.binary(max_size=120),
    st.lists(st.integers(0, 120), max_size=6),
)
def test_client_parser_accounts_for_every_garbage_byte(
    commands_: list[AnyCommand], data: bytes, cuts: list[int]
) -> None:
    # which command a byte is read for depends on when it arrives, so only the accounting is
    # compared across chunkings here
    for chunks in ([data], [bytes((b,)) for b in data], chunked(data, cuts)):
        _, accounted = drive_client(commands_, chunks)
        assert accounted == len(data)


@FAST
@given(commands, st.binary(max_size=60), st.lists(st.integers(0, 60), max_size=6))
def test_one_reply_scans_the_same_in_any_chunking(
    command: AnyCommand, data: bytes, cuts: list[int]
) -> None:
    whole, _ = drive_client([command], [data])
    by_byte, _ = drive_client([command], [bytes((b,)) for b in data])
    by_chunk, _ = drive_client([command], chunked(data, cuts))
    assert merge_unexpected(whole) == merge_unexpected(by_byte) == merge_unexpected(by_chunk)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(exchanges, min_size=1, max_size=3),
    st.binary(max_size=30).filter(lambda garbage: 0xA5 not in garbage),
)
def test_client_recovers_after_garbage_with_reset_and_echo(
    history: list[tuple[AnyCommand, AnyReply]], garbage: bytes
) -> None:
    client = SynScanClientConnection()
    for command, reply in history:
        client.send(command)
        client.receive_data(encode_reply(reply))
        assert client.next_event() == reply
    client.send(GetRaDec())
    client.receive_data(garbage)
    while client.next_event() is not NEED_DATA:
        pass
    client.reset()
    marker = 0xA5
    client.send(Echo(marker))
    client.receive_data(garbage + bytes((marker, HASH)))
    events = []
    while (event := client.next_event()) is not NEED_DATA:
        events.append(event)
    assert events[-1] == EchoReply(marker)
    assert all(isinstance(event, UnexpectedData) for event in events[:-1])
