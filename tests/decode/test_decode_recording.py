"""The recording format (`scopelink.decode.recording`): written, read back, bad lines named."""

from __future__ import annotations

import pytest

from scopelink.decode import Direction, Protocol
from scopelink.decode.recording import (
    RecordingError,
    event_line,
    header_line,
    is_recording,
    read_recording,
)


def test_every_byte_and_time_reads_back_and_exchanges_join_transfers() -> None:
    every_byte = bytes(range(256))
    text = "\n".join(
        [
            header_line(Protocol.SKYTRACKER, device="skytracker:/dev/ttyUSB0"),
            event_line(0.25, Direction.PC, b"Q"),
            event_line(0.2512345678, Direction.DEVICE, b"A"),
            event_line(0.3, Direction.PC, b"\r"),
            event_line(0.3, Direction.PC, every_byte),
            event_line(0.4, Direction.DEVICE, b" 12.345 +67.890\0"),
        ]
    ).encode()
    assert is_recording(text)
    recording = read_recording(text)
    assert recording.protocol is Protocol.SKYTRACKER
    assert recording.header["device"] == "skytracker:/dev/ttyUSB0"
    assert [t.data for t in recording.transfers][3] == every_byte
    assert recording.transfers[1].t == 0.251235  # microseconds are kept, no more
    assert [(e.command, e.reply, e.line) for e in recording.exchanges()] == [
        (b"Q", b"A", 2),
        (b"\r" + every_byte, b" 12.345 +67.890\0", 4),
    ]


@pytest.mark.parametrize(
    ("lines", "message"),
    [
        (['{"t": 0}'], "line 1: not a scopelink recording"),
        (['{"scopelink_recording": 2}'], "line 1: recording format version 2; this scopelink"),
        (['{"scopelink_recording": 1, "protocol": "lx200"}'], "line 1: unknown protocol 'lx200'"),
        (['{"scopelink_recording": 1}', "{nope"], "line 2: not JSON"),
        (
            ['{"scopelink_recording": 1}', '{"t": 2, "dir": "->", "data": "e"}', '{"t": 1}'],
            "line 3: 't' must be seconds, not before 2.0",
        ),
        (
            ['{"scopelink_recording": 1}', '{"t": 1, "dir": "->", "data": "\\\\q"}'],
            "line 2: 'data'",
        ),
    ],
)
def test_a_bad_line_is_named(lines: list[str], message: str) -> None:
    with pytest.raises(RecordingError, match="^" + message.replace("(", r"\(")):
        read_recording("\n".join(lines).encode())
