"""scopelink.decode on SynScan traces: meanings in plain units, pipelining, INDI logs, errors."""

from __future__ import annotations

import pytest

from scopelink.decode import Annotation, Chunk, Direction, Kind, Peer, annotate, parse_trace
from scopelink.protocol import synscan


def _summary(annotations: list[Annotation]) -> list[tuple[int, str, bytes, str]]:
    return [(a.offset, a.kind.value, a.data, a.meaning) for a in annotations]


def _errors(annotations: list[Annotation]) -> list[Annotation]:
    return [a for a in annotations if a.is_error]


def test_issue_example_precise_ra_dec() -> None:
    # Worked independently: 0x34AB05 / 2**24 of a day and 0x12CE05 / 2**24 of a turn.
    ra_hours = 0x34AB05 / 2**24 * 24
    dec_degrees = 0x12CE05 / 2**24 * 360
    assert int(ra_hours) == 4
    assert int(ra_hours * 60 % 60) == 56
    assert round(ra_hours * 3600 % 60, 1) == 15.5
    assert round(dec_degrees, 2) == 26.44

    command, reply = annotate(b"e34AB0500,12CE0500#")

    assert (command.offset, command.data, command.direction) == (0, b"e", Direction.PC)
    assert command.meaning == "get precise RA/Dec"
    assert command.message == synscan.GetRaDec(precise=True)
    assert (reply.offset, reply.data, reply.direction) == (
        1,
        b"34AB0500,12CE0500#",
        Direction.DEVICE,
    )
    assert reply.kind is Kind.REPLY
    assert reply.meaning == "RA 4h 56m 15.5s, Dec +26.44°"
    assert isinstance(reply.message, synscan.Position)


def test_version_reply() -> None:
    assert _summary(annotate(b"V042507#")) == [
        (0, "command", b"V", "get hand control version"),
        (1, "reply", b"042507#", "version 4.37.07"),
    ]


def test_spec_location_example() -> None:
    # 118°20'17" W, 33°50'41" N, as the spec sends it.
    trace = b"W" + bytes((33, 50, 41, 0, 118, 20, 17, 1)) + b"#"
    assert _summary(annotate(trace)) == [
        (0, "command", trace[:9], "set location 33°50'41\"N 118°20'17\"W"),
        (9, "reply", b"#", "ok"),
    ]


def test_spec_time_example() -> None:
    # 3:26:00 PM on April 6, 2005, Eastern time (-5 -> 251), daylight saving on.
    trace = b"H" + bytes((15, 26, 0, 4, 6, 5, 251, 1)) + b"#"
    command, reply = annotate(trace)
    assert command.meaning == "set time 2005-04-06 15:26:00 UTC-5 DST"
    assert reply.meaning == "ok"


def test_time_with_hash_in_payload_is_framed_by_length() -> None:
    # INDI's test vector: minute 0x23 is '#', which must not end anything.
    trace = b"H\x08\x23\x2b\x0c\x12\x11\xfe\x00#"
    command, reply = annotate(trace)
    assert command.data == trace[:9]
    assert command.meaning == "set time 2017-12-18 08:35:43 UTC-2"
    assert (reply.offset, reply.data) == (9, b"#")


def test_passthrough_slews_in_plain_units() -> None:
    trace = b"P\x03\x10\x06\x02\x58\x00\x00#" + b"P\x02\x11\x25\x09\x00\x00\x00#"
    trace += b"P\x04\x10\x17\x9c\x71\xc7\x00#"
    meanings = [a.meaning for a in annotate(trace) if a.kind is Kind.COMMAND]
    assert meanings == [
        "slew RA/Azm + at 150.00 arcsec/s (variable rate)",
        "slew Dec/Alt - at fixed rate 9",
        "slow goto RA/Azm to 220.0000°",
    ]


def test_stellarium_like_session() -> None:
    trace = b"Ka" + b"a#" + b"e" + b"34AB0500,12CE0500#" + b"r20000000,20000000" + b"#"
    trace += b"L" + b"1#" + b"e" + b"20000000,20000000#" + b"L" + b"0#"
    annotations = annotate(trace)
    assert not _errors(annotations)
    assert [a.meaning for a in annotations] == [
        "echo 0x61 ('a')",
        "echo 0x61 ('a')",
        "get precise RA/Dec",
        "RA 4h 56m 15.5s, Dec +26.44°",
        "precise goto RA 3h 00m 00.0s, Dec +45.00°",
        "ok",
        "is goto in progress?",
        "goto in progress",
        "get precise RA/Dec",
        "RA 3h 00m 00.0s, Dec +45.00°",
        "is goto in progress?",
        "no goto in progress",
    ]
    assert [a.direction for a in annotations] == [Direction.PC, Direction.DEVICE] * 6


def test_indi_abort_burst_untagged() -> None:
    annotations = annotate(b"T\x00#M#M#")
    assert _summary(annotations) == [
        (0, "command", b"T\x00", "set tracking mode 0 (off)"),
        (2, "reply", b"#", "ok"),
        (3, "command", b"M", "cancel goto"),
        (4, "reply", b"#", "ok"),
        (5, "command", b"M", "cancel goto"),
        (6, "reply", b"#", "ok"),
    ]


def test_pipelined_commands_are_answered_in_order() -> None:
    chunks = [
        Chunk(b"T\x00", Direction.PC),
        Chunk(b"M", Direction.PC),
        Chunk(b"M", Direction.PC),
        Chunk(b"###", Direction.DEVICE),
    ]
    annotations = annotate(chunks)
    assert not _errors(annotations)
    assert [(a.offset, a.kind.value) for a in annotations] == [
        (0, "command"),
        (2, "command"),
        (3, "command"),
        (4, "reply"),
        (5, "reply"),
        (6, "reply"),
    ]


def test_tagged_input_equals_untagged() -> None:
    untagged = parse_trace([b"e34AB0500,12CE0500#V042507#"])
    tagged = parse_trace(
        [b"> e", b"< 34AB0500,12CE0500#", b"TX: V", b"RX:042507#"],
    )
    arrows = parse_trace([b"-> e", b"<- 34AB0500,12CE0500#", b"PC: V", b"HC: 042507#"])
    assert annotate(tagged) == annotate(untagged) == annotate(arrows)


def test_hex_input_equals_escaped_text() -> None:
    text = parse_trace([b"e", b"34AB0500,12CE0500#", b"H\\x08#+\\x0c\\x12\\x11\\xfe\\0", b"#"])
    hex_dump = parse_trace(
        [
            b"65",
            b"33 34 41 42 30 35 30 30 2c 31 32 43 45 30 35 30 30 23",
            b"0x48,0x08,0x23,0x2B,0x0C,0x12,0x11,0xFE,0x00",
            b"23",
        ],
        hex_input=True,
    )
    assert [chunk.data for chunk in text] == [chunk.data for chunk in hex_dump]
    assert annotate(text) == annotate(hex_dump)


def test_indi_debug_log() -> None:
    log = [
        b"[2024-03-01T21:00:00.001 CET DEBG ] [DEBUG] CMD <Kx>",
        b"[2024-03-01T21:00:00.002 CET DEBG ] [DEBUG] RES <x#>",
        b"[2024-03-01T21:00:00.003 CET INFO ] Firmware version: 4.390700",
        b"[DEBUG] CMD <e>",
        b"[DEBUG] RES <34AB0500,12CE0500#>",
        b"[DEBUG] CMD <54 00>",
        b"[DEBUG] RES <#>",
        b"[DEBUG] CMD <M>",
        b"[DEBUG] CMD <M>",
        b"[DEBUG] CMD <50 02 11 24 00 00 00 00>",
        b"[DEBUG] RES <#>",
    ]
    annotations = annotate(parse_trace(log))
    assert not _errors(annotations)
    meanings = [a.meaning for a in annotations]
    assert meanings[:4] == [
        "echo 0x78 ('x')",
        "echo 0x78 ('x')",
        "get precise RA/Dec",
        "RA 4h 56m 15.5s, Dec +26.44°",
    ]
    # INDI reads no reply to 'M' and flushes its input before the next command.
    notes = [a for a in annotations if a.kind is Kind.NOTE]
    assert len(notes) == 2
    assert all(note.data == b"" and "discarded its input" in note.meaning for note in notes)
    assert meanings[-2:] == ["stop Dec/Alt (fixed rate 0)", "ok"]


def test_indi_short_read_of_binary_reply_is_reported() -> None:
    # INDI reads 'w' until the first '#': latitude 35° (0x23) cuts the reply short.
    annotations = annotate(parse_trace([b"CMD <w>", b"RES <#>", b"CMD <e>"]))
    (error,) = _errors(annotations)
    assert error.data == b"#"
    assert "incomplete reply to 'get location'" in error.meaning


def test_unknown_command_byte_points_at_it() -> None:
    annotations = annotate(b"V042507#XV042507#")
    (error,) = _errors(annotations)
    assert (error.offset, error.data, error.error_offset) == (8, b"X", 8)
    assert error.meaning == "unknown command byte 0x58 ('X')"
    assert [a.meaning for a in annotations[-2:]] == ["get hand control version", "version 4.37.07"]


def test_bad_hex_digit_in_goto_command_points_at_it() -> None:
    annotations = annotate(b"r34AB0500,12CE05G0")
    (error,) = _errors(annotations)
    assert error.data == b"r34AB0500,12CE05G0"
    assert error.error_offset == 16
    assert "expected a hex digit" in error.meaning


def test_bad_hex_digit_in_position_reply_points_at_it_and_resynchronises() -> None:
    annotations = annotate(b"e34AB05G0,12CE0500#V042507#")
    (error,) = _errors(annotations)
    assert error.direction is Direction.DEVICE
    assert (error.offset, error.data, error.error_offset) == (1, b"34AB05G0,12CE0500#", 7)
    assert "expected a hex digit, got 0x47" in error.meaning
    assert [a.meaning for a in annotations[-2:]] == ["get hand control version", "version 4.37.07"]


def test_truncated_reply_is_incomplete() -> None:
    annotations = annotate(b"e34AB0500,12")
    (error,) = _errors(annotations)
    assert error.data == b"34AB0500,12"
    assert error.meaning.startswith("incomplete reply to 'get precise RA/Dec': 11 bytes")
    assert error.error_offset == 11


def test_truncated_command_is_incomplete() -> None:
    (error,) = annotate(b"W\x28\x19")
    assert error.is_error
    assert error.meaning == "incomplete 'W' command: 3 of 9 bytes before the end of the trace"


def test_command_without_reply_at_end_is_only_a_note() -> None:
    command, note = annotate(b"r20000000,20000000")
    assert command.meaning == "precise goto RA 3h 00m 00.0s, Dec +45.00°"
    assert (note.kind, note.data, note.offset) == (Kind.NOTE, b"", 18)


def test_stray_hash_before_a_command_is_a_note() -> None:
    annotations = annotate(b"#V042507#")
    assert [(a.offset, a.kind) for a in annotations] == [
        (0, Kind.NOTE),
        (1, Kind.COMMAND),
        (2, Kind.REPLY),
    ]


def test_device_bytes_nobody_asked_for_are_one_error() -> None:
    annotations = annotate([Chunk(b"#1#", Direction.DEVICE), Chunk(b"J", Direction.PC)])
    error, command, note = annotations
    assert (error.data, error.peer, error.error_offset) == (b"#1#", Peer.SYNSCAN, 0)
    assert (
        error.meaning
        == "3 unexpected bytes from the SynScan hand control: no command awaits a reply"
    )
    assert command.meaning == "is alignment complete?"
    assert note.kind is Kind.NOTE


@pytest.mark.parametrize(
    ("reply", "meaning"),
    [
        (b"\x01#", "aligned"),
        (b"\x00#", "not aligned"),
    ],
)
def test_binary_alignment_reply(reply: bytes, meaning: str) -> None:
    assert annotate(b"J" + reply)[1].meaning == meaning
