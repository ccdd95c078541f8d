"""The LX200 codec: wire forms, what real clients send, round trips, chunking and garbage."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.protocol.lx200 import (
    ASTERISK_DEGREE_SIGN,
    DATE_SET_REPLY,
    DEGREE_SIGN,
    MAX_COMMAND_LENGTH,
    MEADE_DEGREE_SIGN,
    NEED_DATA,
    Ack,
    AnyCommand,
    Direction,
    Get,
    GotoTarget,
    Halt,
    LX200ServerConnection,
    MalformedCommand,
    Move,
    PulseGuide,
    Query,
    ReplyKind,
    SetLatitude,
    SetLocalDate,
    SetLocalTime,
    SetLongitude,
    SetRate,
    SetTargetDec,
    SetTargetRA,
    SetUtcOffset,
    SlewRate,
    SlewRefusal,
    StrayBytes,
    SyncTarget,
    TogglePrecision,
    UnknownCommand,
    degree_sign_of,
    encode_command,
    format_altitude,
    format_azimuth,
    format_dec,
    format_ra,
    parse_command,
    parse_sexagesimal,
    parse_skyfi_query,
    precision_of,
    reply_kind,
    skyfi_reply,
    slew_reply,
    text_reply,
)


def events_of(data: bytes) -> list[object]:
    connection = LX200ServerConnection()
    connection.receive_data(data)
    events: list[object] = []
    while (event := connection.next_event()) is not NEED_DATA:
        events.append(event)
    return events


# --- wire forms ---------------------------------------------------------------------------------


def test_coordinates_in_both_precisions() -> None:
    assert format_ra(12.5) == "12:30:00"
    assert format_ra(12.5, high_precision=False) == "12:30.0"
    assert format_ra(23.99999) == "00:00:00"  # rounds to 24 h, which is 0 h
    assert format_ra(5 + 59 / 60 + 59.6 / 3600) == "06:00:00"
    assert format_dec(-45.5) == "-45\xdf30:00"  # Meade's degree byte unless asked for '*'
    assert format_dec(45.5, high_precision=False, degree_sign="*") == "+45*30"
    assert format_dec(-0.0001, degree_sign="*") == "+00*00:00"  # no negative zero
    assert format_dec(-0.3, degree_sign="*") == "-00*18:00"
    assert format_dec(91.0, degree_sign="*") == "+90*00:00"
    assert format_altitude(-1.25, degree_sign="*") == "-01*15'00"
    assert format_azimuth(359.99999) == "000\xdf00'00"
    assert format_azimuth(180.5, high_precision=False, degree_sign="*") == "180*30"


@pytest.mark.parametrize(
    ("text", "sign"),
    [
        ("+45\xdf22:52", "\xdf"),  # Stellarium
        ("+37*17", "*"),  # SkySafari
        ("+45:22:52", None),  # INDI
        (" -045 * 30", "*"),
        ("45", None),
        ("*45", None),
    ],
)
def test_the_degree_sign_a_client_wrote(text: str, sign: str | None) -> None:
    assert degree_sign_of(text) == sign
    if sign is not None:
        command = parse_command("Sd" + text)
        assert isinstance(command, SetTargetDec)
        assert command.degree_sign == sign


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("12:30:00", 12.5),
        ("12:30.5", 12.508333333333333),
        ("+45*30:15", 45.50416666666667),
        ("-45\xdf30'15", -45.50416666666667),
        ("45*30", 45.5),
        ("+40:24:00", 40.4),
        (" 074:00", 74.0),
        ("-00*30", -0.5),
        ("12:30:15.5", 12.504305555555556),
    ],
)
def test_lenient_sexagesimal(text: str, value: float) -> None:
    parsed = parse_sexagesimal(text)
    assert parsed is not None
    assert parsed == pytest.approx(value, abs=1e-12)


@pytest.mark.parametrize("text", ["", "ab", "12:61", "12:30:60", "12::30", "+-1", "1234"])
def test_not_sexagesimal(text: str) -> None:
    assert parse_sexagesimal(text) is None


# --- what real clients send -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("wire", "command"),
    [
        (b":Sr 12:34:56#", SetTargetRA(12 + 34 / 60 + 56 / 3600)),  # INDI, with a space
        (b":Sr12:34.5#", SetTargetRA(12 + 34.5 / 60)),  # low precision
        (b":Sr 12:34:56.70#", SetTargetRA(12 + 34 / 60 + 56.7 / 3600)),  # INDI's "longer" form
        (b":Sd +45*30:15#", SetTargetDec(45 + 30 / 60 + 15 / 3600)),
        (b":Sd -00:30:00#", SetTargetDec(-0.5)),  # INDI's negative zero
        (b":Sd+45*30#", SetTargetDec(45.5)),
        (b":St+40:24:00#", SetLatitude(40.4)),  # INDI
        (b":St -33*52#", SetLatitude(-(33 + 52 / 60))),
        (b":Sg356:18#", SetLongitude(356.3)),  # INDI sends 360 - east longitude
        (b":SG -02#", SetUtcOffset(-2.0)),
        (b":SG+05.5#", SetUtcOffset(5.5)),
        (b":SL 23:59:58#", SetLocalTime(23, 59, 58)),
        (b":SC 11/22/26#", SetLocalDate(11, 22, 2026)),
        (b":SC02/29/28#", SetLocalDate(2, 29, 2028)),
        (b":Mgn0500#", PulseGuide(Direction.NORTH, 500)),
        (b":Mgw12000#", PulseGuide(Direction.WEST, 12000)),
        (b":MS#", GotoTarget()),
        (b":CM#", SyncTarget()),
        (b":CR#", SyncTarget("CR")),
        (b":Q#", Halt()),
        (b":Qe#", Halt(Direction.EAST)),
        (b":Ms#", Move(Direction.SOUTH)),
        (b":RS#", SetRate(SlewRate.SLEW)),
        (b":RG#", SetRate(SlewRate.GUIDE)),
        (b":U#", TogglePrecision()),
        (b":GVP#", Get(Query.PRODUCT)),
        (b":D#", Get(Query.DISTANCE_BARS)),
        (b"\x06", Ack()),
    ],
)
def test_commands_as_clients_send_them(wire: bytes, command: AnyCommand) -> None:
    [event] = events_of(wire)
    assert same(event, command)


def test_stellarium_prefixes_a_hash_and_commands_stack() -> None:
    events = events_of(b"#:GR##:GD#:Q##\x06#:Mn#")
    assert events == [
        Get(Query.RA),
        Get(Query.DEC),
        Halt(),
        Ack(),
        Move(Direction.NORTH),
    ]


def test_the_longitude_convention() -> None:
    assert SetLongitude(356.3).east_longitude_deg == pytest.approx(3.7)
    assert SetLongitude(74.0).east_longitude_deg == pytest.approx(-74.0)
    assert SetLongitude(-3.7).east_longitude_deg == pytest.approx(3.7)
    assert SetLongitude(180.0).east_longitude_deg == pytest.approx(180.0)


@pytest.mark.parametrize(
    ("wire", "code"),
    [
        (b":Sr 25:00:00#", "Sr"),
        (b":Sr -01:00:00#", "Sr"),
        (b":Sd +95*00#", "Sd"),
        (b":Sd#", "Sd"),
        (b":St north#", "St"),
        (b":SG +15#", "SG"),
        (b":SL 24:00:00#", "SL"),
        (b":SC 02/30/26#", "SC"),
        (b":SC 13/01/26#", "SC"),
        (b":Mgn#", "Mg"),
    ],
)
def test_bad_arguments_are_malformed_and_set_commands_still_get_their_zero(
    wire: bytes, code: str
) -> None:
    [event] = events_of(wire)
    assert isinstance(event, MalformedCommand)
    assert event.code == code
    assert "malformed" in event.describe()
    expected = ReplyKind.NONE if code == "Mg" else ReplyKind.CHAR
    assert reply_kind(event) is expected


def test_unknown_commands_and_stray_bytes_are_reported_and_skipped() -> None:
    events = events_of(b"xyz:hP#:GR#\r\n")
    assert events == [
        StrayBytes(b"xyz"),
        UnknownCommand("hP"),
        Get(Query.RA),
        StrayBytes(b"\r\n"),
    ]
    assert "ignored" in UnknownCommand("hP").describe()
    assert "stray" in StrayBytes(b"x").describe()


def test_an_overlong_command_is_skipped_to_its_hash() -> None:
    connection = LX200ServerConnection()
    connection.receive_data(b":S" + b"x" * (MAX_COMMAND_LENGTH + 5))
    event = connection.next_event()
    assert isinstance(event, MalformedCommand)
    assert "too long" in event.reason
    assert connection.pending
    connection.receive_data(b"yyy#:GD#")
    assert connection.next_event() == Get(Query.DEC)
    assert connection.next_event() is NEED_DATA


def test_a_partial_command_can_be_discarded() -> None:
    connection = LX200ServerConnection()
    connection.receive_data(b":GR")
    assert connection.next_event() is NEED_DATA
    assert connection.pending
    assert connection.discard_partial() == b":GR"
    connection.receive_data(b":GD#")
    assert connection.next_event() == Get(Query.DEC)


def test_reply_kinds_and_replies() -> None:
    assert reply_kind(Get(Query.RA)) is ReplyKind.TERMINATED
    assert reply_kind(SetTargetRA(1.0)) is ReplyKind.CHAR
    assert reply_kind(GotoTarget()) is ReplyKind.SLEW
    assert reply_kind(SetLocalDate(1, 1, 2026)) is ReplyKind.DATE_SET
    assert reply_kind(Move(Direction.EAST)) is ReplyKind.NONE
    assert reply_kind(Ack()) is ReplyKind.CHAR
    assert DATE_SET_REPLY == b"1Updating Planetary Data#" + b" " * 30 + b"#"
    assert slew_reply(None) == b"0"
    assert slew_reply(SlewRefusal.BELOW_HORIZON, "Object below #horizon") == (
        b"1Object below  horizon#"
    )
    assert len(slew_reply(SlewRefusal.OTHER, "x" * 200)) == 42
    assert text_reply("a#b\x7f") == b"a b\x7f#"


def test_skyfi_discovery() -> None:
    query = parse_skyfi_query(b"skyfi:Scope?")
    assert query is not None
    assert query.name == "Scope"
    assert query.matches("scope")
    assert not query.matches("other")
    assert query.matches(None)
    assert skyfi_reply(query, "127.0.0.1") == b"skyfi:Scope@127.0.0.1"
    anyone = parse_skyfi_query(b"skyfi?")
    assert anyone is not None
    assert anyone.name is None
    assert anyone.matches("x")
    assert skyfi_reply(anyone, "10.0.0.1") == b"skyfi@10.0.0.1"
    for not_a_query in (b"skyfi@10.0.0.1", b"hello?", b"skyfiX?", b""):
        assert parse_skyfi_query(not_a_query) is None
    with pytest.raises(ValueError, match="IPv4"):
        skyfi_reply(anyone, "::1")


# --- properties -------------------------------------------------------------------------------


def same(a: object, b: object) -> bool:
    """Equal, with floats compared to a millionth of an arcsecond."""
    if type(a) is not type(b):
        return False
    fields = getattr(a, "__dataclass_fields__", {})
    for name, spec in fields.items():
        if not spec.compare:  # the degree sign a client wrote: how, not what
            continue
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, float):
            if not math.isclose(x, y, abs_tol=1e-9):
                return False
        elif x != y:
            return False
    return True


directions = st.sampled_from(Direction)
ras = st.integers(0, 86399).map(lambda s: s / 3600.0)
decs = st.integers(-90 * 3600, 90 * 3600).map(lambda s: s / 3600.0)
commands: st.SearchStrategy[AnyCommand] = st.one_of(
    st.just(Ack()),
    st.builds(Get, st.sampled_from(Query)),
    st.just(TogglePrecision()),
    st.builds(SetTargetRA, ras),
    st.builds(SetTargetDec, decs),
    st.just(GotoTarget()),
    st.builds(SyncTarget, st.sampled_from(["CM", "CR"])),
    st.builds(Halt, st.none() | directions),
    st.builds(Move, directions),
    st.builds(PulseGuide, directions, st.integers(0, 99999)),
    st.builds(SetRate, st.sampled_from(SlewRate)),
    st.builds(SetLatitude, st.integers(-90 * 60, 90 * 60).map(lambda m: m / 60.0)),
    st.builds(SetLongitude, st.integers(0, 360 * 60 - 1).map(lambda m: m / 60.0)),
    st.builds(SetUtcOffset, st.integers(-140, 140).map(lambda t: t / 10.0)),
    st.builds(SetLocalTime, st.integers(0, 23), st.integers(0, 59), st.integers(0, 59)),
    st.builds(SetLocalDate, st.integers(1, 12), st.integers(1, 28), st.integers(2000, 2099)),
)


@given(commands)
def test_round_trip(command: AnyCommand) -> None:
    [event] = events_of(encode_command(command))
    assert same(event, command), (event, command)


@given(st.integers(0, 14399).map(lambda t: t / 600.0), st.integers(-5400, 5400))
def test_low_precision_round_trip(ra_hours: float, dec_minutes: int) -> None:
    dec = dec_minutes / 60.0
    wire = encode_command(SetTargetRA(ra_hours), high_precision=False) + encode_command(
        SetTargetDec(dec), high_precision=False
    )
    ra_event, dec_event = events_of(wire)
    assert same(ra_event, SetTargetRA(ra_hours))
    assert same(dec_event, SetTargetDec(dec))


@given(st.floats(-1e6, 1e6))
def test_formatted_coordinates_parse_back_within_half_a_unit(value: float) -> None:
    ra = parse_sexagesimal(format_ra(value))
    assert ra is not None
    difference = (ra - value % 24.0 + 12.0) % 24.0 - 12.0
    assert abs(difference) <= 0.5 / 3600 + 1e-9
    dec = max(-90.0, min(90.0, value / 1e4))
    parsed = parse_sexagesimal(format_dec(dec))
    assert parsed is not None
    assert abs(parsed - dec) <= 0.5 / 3600 + 1e-9


@given(st.floats(-720.0, 720.0), st.booleans())
def test_altitude_and_azimuth_parse_back_within_half_a_unit(value: float, precise: bool) -> None:
    unit = 1.0 / 3600 if precise else 1.0 / 60
    az = parse_sexagesimal(format_azimuth(value, high_precision=precise))
    assert az is not None
    assert abs((az - value % 360.0 + 180.0) % 360.0 - 180.0) <= unit / 2 + 1e-9
    alt_value = max(-90.0, min(90.0, value / 8.0))
    alt = parse_sexagesimal(format_altitude(alt_value, high_precision=precise))
    assert alt is not None
    assert abs(alt - alt_value) <= unit / 2 + 1e-9


@given(st.lists(commands, max_size=8), st.data())
def test_chunking_and_stray_hashes_do_not_change_the_commands(
    sent: list[AnyCommand], data: st.DataObject
) -> None:
    stream = b"".join((b"#" if data.draw(st.booleans()) else b"") + encode_command(c) for c in sent)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=10)))
    connection = LX200ServerConnection()
    events: list[object] = []
    start = 0
    for cut in [*cuts, len(stream)]:
        connection.receive_data(stream[start:cut])
        start = cut
        while (event := connection.next_event()) is not NEED_DATA:
            events.append(event)
    assert len(events) == len(sent)
    assert all(same(a, b) for a, b in zip(events, sent, strict=True))


@given(st.binary(max_size=300))
def test_garbage_never_raises_and_commands_after_it_still_parse(garbage: bytes) -> None:
    connection = LX200ServerConnection()
    connection.receive_data(garbage)
    for _ in range(len(garbage) + 1):
        if connection.next_event() is NEED_DATA:
            break
    connection.discard_partial()
    connection.receive_data(b"#:GR#")
    assert connection.next_event() == Get(Query.RA)


@given(st.text(max_size=40))
def test_parse_command_never_raises(text: str) -> None:
    event = parse_command(text)
    assert event is not None


@pytest.mark.parametrize(
    ("text", "high"),
    [("05:35:17", True), ("05:35.3", False), ("+45\xdf22:52", True), ("+45*22", False)],
)
def test_the_precision_a_client_wrote(text: str, high: bool) -> None:
    assert precision_of(text) is high
    command = parse_command(("Sd" if text[0] in "+-" else "Sr") + text)
    assert isinstance(command, SetTargetDec | SetTargetRA)
    assert command.high_precision is high


def test_the_documented_degree_sign_is_the_code_s() -> None:
    """docs/lx200.md: Meade's byte 0xDF before a client writes its own, and '*' kept for those
    that write it."""
    text = (Path(__file__).parents[2] / "docs" / "lx200.md").read_text(encoding="utf-8")
    row = next(line for line in text.splitlines() if line.startswith("| Degree sign |"))
    assert "before that (and after a client's `:`, INDI's choice) Meade's byte 0xDF" in row
    assert "0xDF or `*`" in row
    assert DEGREE_SIGN == MEADE_DEGREE_SIGN == "\xdf"
    assert ASTERISK_DEGREE_SIGN == "*"
    assert format_dec(1.0)[3] == DEGREE_SIGN


def test_the_client_side_writes_the_degree_sign_a_command_carries() -> None:
    """SkySafari's ASCII '*' unless the command says otherwise (Stellarium's 0xDF)."""
    assert encode_command(SetTargetDec(45.5)) == b":Sd+45*30:00#"
    assert encode_command(SetTargetDec(45.5, "\xdf")) == b":Sd+45\xdf30:00#"
    assert encode_command(SetLatitude(37.25)) == b":St+37*15#"
    assert encode_command(SetLongitude(3.5, "\xdf")) == b":Sg003\xdf30#"
