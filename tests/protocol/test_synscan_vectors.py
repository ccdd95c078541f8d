"""Worked examples of the SynScan spec and NOTES.md, byte for byte, in both directions."""

from __future__ import annotations

import datetime as dt

import pytest

from scopelink.protocol.synscan import (
    NEED_DATA,
    Ack,
    Aligned,
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
    Model,
    ParsedCommand,
    Passthrough,
    PassthroughFailed,
    PassthroughReply,
    PointingSide,
    PointingState,
    Position,
    ReplyError,
    SetAxisPosition,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SlowGoto,
    SyncRaDec,
    Tracking,
    TrackingModeReply,
    UnknownCommand,
    VariableRateSlew,
    Version,
    VersionDialect,
    angles,
    decode_command_frame,
    encode_command,
    encode_reply,
    parse_reply,
    passthrough_command,
    reply_shape,
)


def parse_position(command: GetRaDec | GetAzAlt, data: bytes) -> Position:
    reply = parse_reply(command, data)
    assert isinstance(reply, Position)
    return reply


def server_events(data: bytes) -> list[object]:
    parser = CommandParser()
    parser.receive_data(data)
    events: list[object] = []
    while (event := parser.next_event()) is not NEED_DATA:
        events.append(event)
    return events


# ---------------------------------------------------------------------------------- spec positions


def test_standard_dec_example_is_26_4441_degrees() -> None:
    reply = parse_position(GetRaDec(precise=False), b"34AB,12CE#")
    assert reply == Position(Frame.EQUATORIAL, 0x34AB, 0x12CE, precise=False)
    assert reply.dec_degrees == pytest.approx(26.4441, abs=5e-5)
    assert reply.ra_hours == pytest.approx(0x34AB / 65536 * 24)


def test_precise_azimuth_example_is_26_2519_degrees() -> None:
    reply = parse_position(GetAzAlt(precise=True), b"12AB0500,40000500#")
    assert reply == Position(Frame.HORIZONTAL, 0x12AB0500, 0x40000500, precise=True)
    assert reply.az_degrees == pytest.approx(26.2519, abs=5e-5)
    assert reply.az_degrees == pytest.approx(26.252, abs=5e-4)
    assert reply.alt_degrees == pytest.approx(90.0, abs=2e-4)


def test_spec_reply_examples_parse() -> None:
    assert parse_position(GetRaDec(precise=True), b"34AB0500,12CE0500#").precise
    assert parse_position(GetAzAlt(precise=False), b"12AB,4000#").alt_degrees == 90.0


def test_ra_3h_dec_45_in_both_precisions() -> None:
    assert encode_command(GotoRaDec.from_hours_degrees(3.0, 45.0, precise=False)) == b"R2000,2000"
    assert encode_command(GotoRaDec.from_hours_degrees(3.0, 45.0)) == b"r20000000,20000000"
    assert server_events(b"R2000,2000") == [GotoRaDec(0x2000, 0x2000, precise=False)]
    goto = server_events(b"r20000000,20000000")[0]
    assert isinstance(goto, GotoRaDec)
    assert (goto.ra_hours, goto.dec_degrees) == (3.0, 45.0)


def test_minus_90_degrees_is_c0000000() -> None:
    assert angles.degrees_to_units(-90.0, precise=True) == 0xC0000000
    assert angles.degrees_to_units(-90.0, precise=False) == 0xC000
    assert encode_command(GotoAzAlt.from_degrees(0.0, -90.0)) == b"b00000000,C0000000"
    assert parse_position(GetRaDec(), b"00000000,C0000000#").dec_degrees == -90.0


def test_dec_above_90_is_folded_and_flagged() -> None:
    units = angles.degrees_to_units(100.0, precise=True)
    reply = Position(Frame.EQUATORIAL, 0, units)
    assert reply.dec_degrees == pytest.approx(80.0)
    assert reply.flipped
    assert "over the pole" in reply.describe()
    assert angles.fold_over_pole(-100.0) == (-80.0, True)
    assert angles.fold_over_pole(45.0) == (45.0, False)
    assert not Position.from_ra_dec(1.0, -89.0).flipped


def test_precise_values_are_emitted_with_low_byte_00() -> None:
    for degrees in (0.1, 123.456789, 359.99999, -12.3456):
        assert angles.degrees_to_units(degrees, precise=True) & 0xFF == 0


def test_lowercase_hex_is_accepted_both_ways() -> None:
    assert server_events(b"r2000abcd,c0000000") == [GotoRaDec(0x2000ABCD, 0xC0000000)]
    assert server_events(b"s34ab0500,12ce0500") == [SyncRaDec(0x34AB0500, 0x12CE0500)]
    assert server_events(b"b12ab0500,40000500") == [GotoAzAlt(0x12AB0500, 0x40000500)]
    assert parse_position(GetRaDec(), b"34ab0500,12ce0500#") == Position(
        Frame.EQUATORIAL, 0x34AB0500, 0x12CE0500
    )


def test_replies_are_encoded_in_uppercase() -> None:
    reply = Position(Frame.EQUATORIAL, 0xABCDEF00, 0x12AB0500)
    assert encode_reply(reply) == b"ABCDEF00,12AB0500#"
    assert encode_reply(Position(Frame.HORIZONTAL, 0xABCD, 0xEF, precise=False)) == b"ABCD,00EF#"


def test_describe_position_in_plain_units() -> None:
    reply = Position.from_ra_dec(4 + 57 / 60 + 12.3 / 3600, 26.44)
    assert reply.describe() == "RA 4h 57m 12.3s, Dec +26.44°"
    assert str(reply) == reply.describe()
    alt_az = Position.from_az_alt(26.25, -5.5, precise=False)
    assert alt_az.describe() == "Az 26.25°, Alt -5.50°"


# ----------------------------------------------------------------------------- rates and positions


def test_rate_150_arcsec_per_second_is_bytes_2_88() -> None:
    assert angles.rate_units_to_bytes(angles.rate_to_units(150.0)) == (2, 88)
    slew = VariableRateSlew.from_arcsec_per_second(Axis.AZM_RA, 150.0)
    assert encode_command(slew) == bytes((ord("P"), 3, 16, 6, 2, 88, 0, 0))
    assert slew.arcsec_per_second == 150.0


def test_rate_above_protocol_maximum_is_refused() -> None:
    with pytest.raises(ValueError, match="maximum"):
        angles.rate_to_units(20000.0)


def test_220_degrees_is_bytes_156_113_199() -> None:
    assert angles.degrees_to_position24(220.0) == 10_252_743
    assert angles.position24_to_bytes(10_252_743) == (156, 113, 199)


@pytest.mark.parametrize(
    ("command", "wire"),
    [
        (VariableRateSlew(Axis.AZM_RA, True, 600), (3, 16, 6, 2, 88, 0, 0)),
        (VariableRateSlew(Axis.AZM_RA, False, 600), (3, 16, 7, 2, 88, 0, 0)),
        (VariableRateSlew(Axis.ALT_DEC, True, 600), (3, 17, 6, 2, 88, 0, 0)),
        (VariableRateSlew(Axis.ALT_DEC, False, 600), (3, 17, 7, 2, 88, 0, 0)),
        (FixedRateSlew(Axis.AZM_RA, True, 9), (2, 16, 36, 9, 0, 0, 0)),
        (FixedRateSlew(Axis.AZM_RA, False, 1), (2, 16, 37, 1, 0, 0, 0)),
        (FixedRateSlew(Axis.ALT_DEC, True, 0), (2, 17, 36, 0, 0, 0, 0)),
        (FixedRateSlew(Axis.ALT_DEC, False, 5), (2, 17, 37, 5, 0, 0, 0)),
        (GetDeviceVersion(Axis.AZM_RA), (1, 16, 254, 0, 0, 0, 2)),
        (GetDeviceVersion(Axis.ALT_DEC), (1, 17, 254, 0, 0, 0, 2)),
        (SlowGoto.from_degrees(Axis.AZM_RA, 220.0), (4, 16, 23, 156, 113, 199, 0)),
        (SlowGoto.from_degrees(Axis.ALT_DEC, 220.0), (4, 17, 23, 156, 113, 199, 0)),
        (SetAxisPosition.from_degrees(Axis.AZM_RA, 220.0), (4, 16, 4, 156, 113, 199, 0)),
        (SetAxisPosition.from_degrees(Axis.ALT_DEC, 220.0), (4, 17, 4, 156, 113, 199, 0)),
    ],
)
def test_passthrough_byte_layouts(command: object, wire: tuple[int, ...]) -> None:
    frame = b"P" + bytes(wire)
    assert encode_command(command) == frame  # type: ignore[arg-type]
    assert server_events(frame) == [command]


def test_other_passthrough_payloads_stay_raw_with_their_reply_length() -> None:
    payload = bytes((3, 178, 132, 7, 226, 0, 0))
    assert passthrough_command(payload) == Passthrough(payload)
    fixed_rate_10 = bytes((2, 16, 36, 10, 0, 0, 0))
    assert server_events(b"P" + fixed_rate_10) == [Passthrough(fixed_rate_10)]
    query = Passthrough(bytes((1, 16, 0x47, 0, 0, 0, 1)))
    assert query.reply_length == 1
    assert parse_reply(query, b"\x80#") == PassthroughReply(b"\x80")
    assert reply_shape(query).lengths == (2, 3)


def test_typed_payload_is_refused_as_raw_passthrough() -> None:
    with pytest.raises(ValueError, match="GetDeviceVersion"):
        Passthrough(bytes((1, 16, 254, 0, 0, 0, 2)))


# ---------------------------------------------------------------------------------- time and place


def test_spec_location_example() -> None:
    wire = b"W" + bytes((33, 50, 41, 0, 118, 20, 17, 1))
    location = Location(33, 50, 41, False, 118, 20, 17, True)
    assert server_events(wire) == [SetLocation(location)]
    assert encode_command(SetLocation(location)) == wire
    assert location.latitude == pytest.approx(33 + 50 / 60 + 41 / 3600)
    assert location.longitude == pytest.approx(-(118 + 20 / 60 + 17 / 3600))
    assert Location.from_degrees(location.latitude, location.longitude) == location
    assert location.describe() == "33°50'41\"N 118°20'17\"W"


def test_notes_location_example() -> None:
    wire = bytes.fromhex("28 19 00 00 03 2A 01 01")
    location = Location(40, 25, 0, False, 3, 42, 1, True)
    assert server_events(b"W" + wire) == [SetLocation(location)]
    assert parse_reply(GetLocation(), wire + b"#") == location


def test_spec_time_example() -> None:
    wire = b"H" + bytes((15, 26, 0, 4, 6, 5, 251, 1))
    time = DateTime(15, 26, 0, 4, 6, 2005, -5, True)
    assert server_events(wire) == [SetTime(time)]
    assert encode_command(SetTime(time)) == wire
    local = time.to_datetime()
    assert local == dt.datetime(2005, 4, 6, 15, 26, tzinfo=dt.timezone(dt.timedelta(hours=-4)))
    assert DateTime.from_datetime(local, dst=True) == time
    assert time.describe() == "2005-04-06 15:26:00 UTC-5 DST"


def test_notes_time_example_with_minute_equal_to_hash() -> None:
    wire = bytes.fromhex("08 23 2B 0C 12 11 FE 00")
    time = DateTime(8, 35, 43, 12, 18, 2017, -2, False)
    assert server_events(b"H" + wire) == [SetTime(time)]
    assert parse_reply(GetTime(), wire + b"#") == time


def test_zone_byte_is_twos_complement() -> None:
    assert encode_command(SetTime(DateTime(0, 0, 0, 1, 1, 2020, -5, False)))[7] == 251
    assert encode_command(SetTime(DateTime(0, 0, 0, 1, 1, 2020, 9, False)))[7] == 9


def test_from_datetime_refuses_naive_and_fractional_zones() -> None:
    with pytest.raises(ValueError, match="aware"):
        DateTime.from_datetime(dt.datetime(2020, 1, 1))
    india = dt.timezone(dt.timedelta(hours=5, minutes=30))
    with pytest.raises(ValueError, match="whole hours"):
        DateTime.from_datetime(dt.datetime(2020, 1, 1, tzinfo=india))


def test_replies_full_of_hash_bytes_are_read_by_length() -> None:
    location = Location(35, 35, 35, False, 35, 35, 35, False)
    wire = bytes((35, 35, 35, 0, 35, 35, 35, 0)) + b"#"
    assert encode_reply(location) == wire
    assert parse_reply(GetLocation(), wire) == location
    time = DateTime(35, 35, 35, 35, 35, 2035, 35, False)
    assert parse_reply(GetTime(), encode_reply(time)) == time


def test_flag_bytes_other_than_0_or_1_are_malformed() -> None:
    [event] = server_events(b"W" + bytes((33, 50, 41, 2, 118, 20, 17, 1)))
    assert isinstance(event, MalformedCommand)
    assert (event.index, event.offset, event.error_offset) == (4, 0, 4)
    [event] = server_events(b"#H" + bytes((15, 26, 0, 4, 6, 5, 251, 7)))
    assert isinstance(event, MalformedCommand)
    assert (event.index, event.error_offset) == (8, 9)


# ----------------------------------------------------------------------------------- small replies


def test_echo_replies() -> None:
    assert encode_command(Echo(ord("#"))) == b"K#"
    assert encode_reply(EchoReply(ord("#"))) == b"##"
    assert parse_reply(Echo(ord("#")), b"##") == EchoReply(ord("#"))
    assert encode_command(Echo(0)) == b"K\x00"
    assert parse_reply(Echo(0), b"\x00#") == EchoReply(0)
    with pytest.raises(ReplyError):
        parse_reply(Echo(ord("a")), b"b#")


def test_version_dialects() -> None:
    assert parse_reply(GetVersion(), b"042507#") == Version(4, 0x25, 7)
    assert Version(4, 0x25, 7).describe() == "version 4.37.07"
    assert encode_reply(Version(4, 37, 7)) == b"042507#"
    nexstar = parse_reply(GetVersion(), b"\x04\x15#")
    assert nexstar == Version(4, 21, None, VersionDialect.NEXSTAR_BINARY)
    old = parse_reply(GetVersion(), b"\x03\x23\x05#")
    assert old == Version(3, 35, 5, VersionDialect.SYNSCAN_BINARY)
    assert old.as_tuple() == (3, 35, 5) > (3, 27, 0)
    assert parse_reply(GetVersion(), b"03270a#") == Version(3, 39, 10)


def test_version_ambiguous_binary_forms_are_refused() -> None:
    with pytest.raises(ValueError, match="hex digit"):
        Version(0x30, 1, None, VersionDialect.NEXSTAR_BINARY)
    with pytest.raises(ValueError, match="35"):
        Version(3, 1, 35, VersionDialect.SYNSCAN_BINARY)


def test_model_reply_and_swapped_dialect() -> None:
    assert parse_reply(GetModel(), b"\x05#") == Model(5)
    assert Model(5).name == "AZ-EQ6 GOTO"
    assert parse_reply(GetModel(), b"#\xa5") == Model(165, swapped=True)
    assert encode_reply(Model(165, swapped=True)) == b"#\xa5"
    assert Model(130).name == "AZ GOTO"
    assert Model(150).name == "Dob GOTO"
    assert not Model(165).is_equatorial
    with pytest.raises(ReplyError):
        parse_reply(GetModel(), b"\x05\x06")


def test_j_is_binary_and_l_is_ascii() -> None:
    assert encode_reply(Aligned(True)) == b"\x01#"
    assert encode_reply(Aligned(False)) == b"\x00#"
    assert parse_reply(IsAligned(), b"\x01#") == Aligned(True)
    with pytest.raises(ReplyError):
        parse_reply(IsAligned(), b"1#")
    assert encode_reply(GotoInProgress(True)) == b"1#"
    assert parse_reply(IsGotoInProgress(), b"0#") == GotoInProgress(False)
    with pytest.raises(ReplyError):
        parse_reply(IsGotoInProgress(), b"\x00#")


def test_pointing_state_and_tracking_mode() -> None:
    assert parse_reply(GetPointingState(), b"W#") == PointingState(PointingSide.WEST)
    assert encode_reply(PointingState(PointingSide.EAST)) == b"E#"
    assert parse_reply(GetTrackingMode(), b"\x02#") == TrackingModeReply(Tracking.EQUATORIAL)
    assert encode_command(SetTrackingMode(Tracking.OFF)) == b"T\x00"
    assert "equatorial" in TrackingModeReply(2).describe()


def test_device_version_reply() -> None:
    assert parse_reply(GetDeviceVersion(Axis.ALT_DEC), b"\x02\x0f#") == DeviceVersion(2, 15)
    assert encode_reply(DeviceVersion(2, 15)) == b"\x02\x0f#"


def test_failed_passthrough_has_one_extra_byte_before_hash() -> None:
    slew = FixedRateSlew(Axis.AZM_RA, True, 9)
    assert parse_reply(slew, b"#") == Ack()
    assert parse_reply(slew, b"\x01#") == PassthroughFailed(b"", 1)
    version = GetDeviceVersion(Axis.AZM_RA)
    assert parse_reply(version, b"\x00\x00\x05#") == PassthroughFailed(b"\x00\x00", 5)
    assert encode_reply(PassthroughFailed(b"\x00\x00", 5)) == b"\x00\x00\x05#"


@pytest.mark.parametrize(
    "command",
    [GotoRaDec(0, 0), SyncRaDec(0, 0, False), GotoAzAlt(0, 0), SetTrackingMode(2), CancelGoto()],
)
def test_commands_answered_by_a_bare_hash(command: object) -> None:
    assert parse_reply(command, b"#") == Ack()  # type: ignore[arg-type]
    assert reply_shape(command).lengths == (1,)  # type: ignore[arg-type]


def test_reply_shapes_give_exact_lengths() -> None:
    assert reply_shape(GetRaDec(precise=True)).lengths == (18,)
    assert reply_shape(GetAzAlt(precise=False)).lengths == (10,)
    assert reply_shape(GetLocation()).lengths == (9,)
    assert set(reply_shape(GetVersion()).lengths) == {7, 3, 4}
    assert reply_shape(GetDeviceVersion(Axis.AZM_RA)).lengths == (3, 4)


def test_parse_reply_refuses_trailing_and_missing_bytes() -> None:
    with pytest.raises(ReplyError, match="follow"):
        parse_position(GetRaDec(False), b"34AB,12CE##")
    with pytest.raises(ReplyError, match="incomplete"):
        parse_position(GetRaDec(False), b"34AB,12CE")
    with pytest.raises(ReplyError, match="hex digit"):
        parse_position(GetRaDec(False), b"34AG,12CE#")


# ---------------------------------------------------------------------------------- server framing


def test_stray_hash_before_a_command_is_skipped() -> None:
    assert server_events(b"V#") == [GetVersion()]
    assert server_events(b"#V##e#") == [GetVersion(), GetRaDec(precise=True)]


def test_back_to_back_abort_comes_out_in_order() -> None:
    assert server_events(b"T\x00MM") == [SetTrackingMode(0), CancelGoto(), CancelGoto()]


def test_unknown_byte_is_reported_and_skipped() -> None:
    events = server_events(b"Xe")
    assert events == [UnknownCommand(ord("X"), 0), GetRaDec(precise=True)]
    assert "0x58" in str(events[0])


def test_malformed_frame_is_discarded_whole() -> None:
    # a goto frame whose payload holds 'B' and 'M' must never start another goto or a cancel
    events = server_events(b"R12B4,M000e")
    [error, command] = events
    assert isinstance(error, MalformedCommand)
    assert error.frame == b"R12B4,M000"
    assert (error.index, error.error_offset) == (6, 6)
    assert command == GetRaDec(precise=True)


def test_missing_comma_is_malformed_at_its_index() -> None:
    [error] = server_events(b"#r123456781234567890")[:1]
    assert isinstance(error, MalformedCommand)
    assert (error.offset, error.index) == (1, 9)


def test_discard_partial_returns_the_incomplete_frame() -> None:
    parser = CommandParser()
    parser.receive_data(b"eR12")
    assert parser.next_event() == GetRaDec()
    assert parser.next_event() is NEED_DATA
    assert parser.discard_partial() == b"R12"
    parser.receive_data(b"J")
    frame = parser.next_frame()
    assert frame == ParsedCommand(IsAligned(), b"J", 4)


@pytest.mark.parametrize(
    ("letter", "length"),
    [
        *((c, 1) for c in "EeZztVmJLMpwh"),
        *((c, 2) for c in "KT"),
        *((c, 9) for c in "WH"),
        *((c, 10) for c in "RBS"),
        *((c, 18) for c in "rbs"),
        ("P", 8),
    ],
)
def test_frame_lengths(letter: str, length: int) -> None:
    parser = CommandParser()
    parser.receive_data(letter.encode() + b"0" * (length - 2))
    if length > 1:
        assert parser.next_event() is NEED_DATA
    parser.receive_data(b"0")
    assert parser.next_event() is not NEED_DATA
    assert parser.offset == length


def test_decode_command_frame_names_every_letter() -> None:
    assert decode_command_frame(b"h") == GetTime()
    assert decode_command_frame(b"w") == GetLocation()
    assert decode_command_frame(b"V") == GetVersion()
    assert decode_command_frame(b"p") == GetPointingState()
    assert decode_command_frame(b"m") == GetModel()
    assert decode_command_frame(b"L") == IsGotoInProgress()
    assert decode_command_frame(b"t") == GetTrackingMode()
    assert decode_command_frame(b"Z") == GetAzAlt(precise=False)
    with pytest.raises(ValueError, match="no command"):
        decode_command_frame(b"X")
