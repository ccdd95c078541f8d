"""Reading trace text: escapes, hex, direction tags, INDI log lines, and where input is wrong."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.decode import (
    Chunk,
    Direction,
    TraceInputError,
    escape_bytes,
    indi_chunk,
    parse_hex,
    parse_trace,
    split_tag,
    unescape,
)


@pytest.mark.parametrize(
    ("text", "data"),
    [
        (rb"L99 12.345 +67.890\r", b"L99 12.345 +67.890\r"),
        (rb"\n\t\0\\", b"\n\t\x00\\"),
        (rb"T\x00\xFe", b"T\x00\xfe"),
        (rb"\01", b"\x001"),
        (b"plain", b"plain"),
    ],
)
def test_unescape(text: bytes, data: bytes) -> None:
    assert unescape(text) == data


@pytest.mark.parametrize(
    ("text", "column"),
    [(rb"e\q", 1), (rb"ab\x4", 2), (rb"\xZZ", 0), (b"tail\\", 4)],
)
def test_bad_escape_points_at_the_backslash(text: bytes, column: int) -> None:
    with pytest.raises(TraceInputError) as raised:
        unescape(text)
    assert raised.value.column == column


@given(st.binary(max_size=64))
def test_escape_round_trips(data: bytes) -> None:
    text = escape_bytes(data)
    assert text.isascii()
    assert "\n" not in text
    assert "\r" not in text
    assert unescape(text.encode("ascii")) == data


@pytest.mark.parametrize(
    ("text", "data"),
    [
        (b"65 33 34", b"e34"),
        (b"0x65,0x33, 0X34", b"e34"),
        (b"65:33:34", b"e34"),
        (b"653334", b"e34"),
        (b"0xD", b"\r"),
        (b"  ", b""),
    ],
)
def test_parse_hex(text: bytes, data: bytes) -> None:
    assert parse_hex(text) == data


@pytest.mark.parametrize(
    ("text", "column"),
    [(b"65 3G", 4), (b"65 333", 3), (b"0xZ1", 2), (b"0x", 0)],
)
def test_bad_hex_points_at_the_character(text: bytes, column: int) -> None:
    with pytest.raises(TraceInputError) as raised:
        parse_hex(text)
    assert raised.value.column == column


@pytest.mark.parametrize(
    ("line", "direction", "rest"),
    [
        (b"> e", Direction.PC, b"e"),
        (b"->e", Direction.PC, b"e"),
        (b"<- #", Direction.DEVICE, b"#"),
        (b"< #", Direction.DEVICE, b"#"),
        (b"TX:\te", Direction.PC, b"e"),
        (b"RX: #", Direction.DEVICE, b"#"),
        (b"PC: Q", Direction.PC, b"Q"),
        (b"HC: #", Direction.DEVICE, b"#"),
        (b"ST: A", Direction.DEVICE, b"A"),
        (b"SC:  12.345", Direction.DEVICE, b" 12.345"),
        (b"e", None, b"e"),
        (b" > e", None, b" > e"),
    ],
)
def test_direction_tags(line: bytes, direction: Direction | None, rest: bytes) -> None:
    assert split_tag(line)[:2] == (direction, rest)


def test_lines_and_arguments_are_chunks() -> None:
    assert parse_trace([b"> e\n< 1\\r", b"", b"V\r\n"]) == [
        Chunk(b"e", Direction.PC),
        Chunk(b"1\r", Direction.DEVICE),
        Chunk(b"V"),
    ]


def test_input_error_reports_the_whole_line_and_column() -> None:
    with pytest.raises(TraceInputError) as raised:
        parse_trace([b"TX: 65 3G"], hex_input=True)
    assert (raised.value.line, raised.value.column) == (b"TX: 65 3G", 8)


@pytest.mark.parametrize(
    ("line", "chunk"),
    [
        (b"[DEBUG] CMD <e>", Chunk(b"e", Direction.PC, flushes_input=True)),
        (b"[DEBUG] RES <34AB,12CE#>", Chunk(b"34AB,12CE#", Direction.DEVICE)),
        (
            b'x "[DEBUG] CMD <50 02 11 24 05 00 00 00> "',
            Chunk(b"P\x02\x11\x24\x05\x00\x00\x00", Direction.PC, flushes_input=True),
        ),
        (b"RES <<#>", Chunk(b"<#", Direction.DEVICE)),
        (b"[DEBUG] CMD: 0XD", Chunk(b"\r", Direction.PC, flushes_input=True)),
        (b"[DEBUG] RES:  12.345 +67.890", Chunk(b" 12.345 +67.890\0", Direction.DEVICE)),
        (b"Mount UTC Time 2024-01-01T10:00:00 Offset 1", None),
    ],
)
def test_indi_lines(line: bytes, chunk: Chunk | None) -> None:
    assert indi_chunk(line) == chunk


def test_an_indi_log_ignores_its_other_lines() -> None:
    log = [b"INFO Firmware version: 4.39", b"CMD <V>", b"garbage \\q", b"RES <042507#>"]
    assert [chunk.data for chunk in parse_trace(log)] == [b"V", b"042507#"]
