"""scopelink.decode on Sky Tracker traces (Sky Commander behind the bus) and Sky Commander alone."""

from __future__ import annotations

from scopelink.decode import (
    Annotation,
    Chunk,
    Direction,
    Kind,
    Peer,
    Protocol,
    annotate,
    parse_trace,
)
from scopelink.protocol import skytracker

TRACKER = Protocol.SKYTRACKER


def _rows(annotations: list[Annotation]) -> list[tuple[int, str, str, bytes, str]]:
    return [(a.offset, a.direction.value, a.peer.name, a.data, a.meaning) for a in annotations]


def test_spec_operating_example() -> None:
    trace = b"QAL99 12.345 +67.890\rAqG"
    assert _rows(annotate(trace, TRACKER)) == [
        (0, "pc", "SKY_TRACKER", b"Q", "Q: request the Sky Commander bus"),
        (
            1,
            "device",
            "SKY_TRACKER",
            b"A",
            "A: bus granted (bytes now relayed to the Sky Commander until 'q')",
        ),
        (
            2,
            "pc",
            "SKY_COMMANDER",
            b"L99 12.345 +67.890\r",
            "L99: load RA 12h 20m 42s, Dec +67.890° as current object",
        ),
        (21, "device", "SKY_COMMANDER", b"A", "A: acknowledged"),
        (22, "pc", "SKY_TRACKER", b"q", "q: release the Sky Commander bus"),
        (23, "pc", "SKY_TRACKER", b"G", "G: enter GOTO mode"),
    ]


def test_spec_realign_sequence() -> None:
    annotations = annotate(b"QAL99 12.345 +67.890\rANq", TRACKER)
    assert not any(a.is_error for a in annotations)
    realign, release = annotations[-2:]
    assert (realign.offset, realign.peer, realign.meaning) == (
        22,
        Peer.SKY_COMMANDER,
        "N: realign on the current object",
    )
    assert isinstance(realign.message, skytracker.Realign)
    assert (release.data, release.peer) == (b"q", Peer.SKY_TRACKER)


def test_same_letter_means_different_things_either_side_of_the_bus() -> None:
    trace = b"R\x20" + b"QA" + b"R" + bytes.fromhex("40000000 C0800000") + b"q"
    status, _, _, _, rates, reply, _ = annotate(trace, TRACKER)
    assert (status.peer, status.meaning) == (Peer.SKY_TRACKER, "R: read status")
    assert (rates.peer, rates.meaning) == (Peer.SKY_COMMANDER, "R: read drive rates")
    assert reply.meaning.startswith("drive rates: Alt +0.5°/min, Az -1°/min")


def test_status_byte_flags() -> None:
    _, reply = annotate(b"R\x28", TRACKER)
    assert reply.meaning == (
        "status 0x28: GUIDE (SPEED: tracking; arrows move at the guide speed); pressed: up"
    )


def test_refused_bus_keeps_bytes_for_the_tracker() -> None:
    annotations = annotate(b"Q\x00U", TRACKER)
    assert _rows(annotations)[1:] == [
        (1, "device", "SKY_TRACKER", b"\x00", "NUL: bus refused (GOTO running)"),
        (2, "pc", "SKY_TRACKER", b"U", "U: enter UTILITY mode"),
    ]


def test_position_request_through_the_bus() -> None:
    trace = b"QA\r 12.345 +67.890\0q"
    reply = annotate(trace, TRACKER)[3]
    assert (reply.offset, reply.data) == (3, b" 12.345 +67.890\0")
    assert reply.meaning == "position RA 12h 20m 42s, Dec +67.890°"


def test_sky_commander_alone_position_reply() -> None:
    command, reply = annotate(b"\r 05.500 -12.250\0", Protocol.SKYCOMMANDER)
    assert (command.peer, command.meaning) == (Peer.SKY_COMMANDER, "CR: read position")
    assert reply.meaning == "position RA 05h 30m 00s, Dec -12.250°"


def test_indi_sky_commander_log() -> None:
    # skycommander.cpp prints the CR with %#02X and the reply with %s (which stops at its NUL).
    log = [b"[DEBUG] CMD: 0XD", b"[DEBUG] RES:  12.345 +67.890", b"[DEBUG] CMD: 0XD"]
    annotations = annotate(parse_trace(log), Protocol.SKYCOMMANDER)
    assert [a.kind for a in annotations] == [Kind.COMMAND, Kind.REPLY, Kind.COMMAND, Kind.NOTE]
    assert annotations[1].data == b" 12.345 +67.890\0"


def test_tagged_bytes_after_q_wait_for_the_answer() -> None:
    chunks = [
        Chunk(b"Q", Direction.PC),
        Chunk(b"\r", Direction.PC),
        Chunk(b"A", Direction.DEVICE),
        Chunk(b" 12.345 +67.890\0", Direction.DEVICE),
        Chunk(b"q", Direction.PC),
    ]
    annotations = annotate(chunks, TRACKER)
    assert not any(a.is_error for a in annotations)
    assert [(a.offset, a.peer, a.kind) for a in annotations] == [
        (0, Peer.SKY_TRACKER, Kind.COMMAND),
        (1, Peer.SKY_COMMANDER, Kind.COMMAND),
        (2, Peer.SKY_TRACKER, Kind.REPLY),
        (3, Peer.SKY_COMMANDER, Kind.REPLY),
        (19, Peer.SKY_TRACKER, Kind.COMMAND),
    ]


def test_garbled_bus_answer_is_an_error_and_counts_as_refused() -> None:
    annotations = annotate(b"QxG", TRACKER)
    error = annotations[1]
    assert (error.kind, error.error_offset) == (Kind.ERROR, 1)
    assert "expected bus grant 'A' or refusal NUL" in error.meaning
    assert annotations[2].meaning == "G: enter GOTO mode"


def test_q_cuts_an_unfinished_line() -> None:
    annotations = annotate(b"QAL99 12.3q", TRACKER)
    error = next(a for a in annotations if a.is_error)
    assert (error.offset, error.data, error.peer) == (2, b"L99 12.3", Peer.SKY_COMMANDER)
    assert "cut short by 'q'" in error.meaning
    assert annotations[-1].meaning == "q: release the Sky Commander bus"


def test_unknown_byte_and_malformed_line() -> None:
    annotations = annotate(b"XQAL77 12.345 +67.890\r", TRACKER)
    unknown, _, _, malformed = annotations
    assert (unknown.data, unknown.error_offset, unknown.kind) == (b"X", 0, Kind.ERROR)
    assert (malformed.offset, malformed.peer, malformed.kind) == (3, Peer.SKY_COMMANDER, Kind.ERROR)


def test_truncated_reply_and_payload() -> None:
    reply_cut = annotate(b"V v4.0", TRACKER)
    assert reply_cut[-1].is_error
    assert reply_cut[-1].meaning.startswith("incomplete reply to 'V: read version': 5 of 8 bytes")
    payload_cut = annotate(b"K\x10", TRACKER)
    (error,) = payload_cut
    assert (error.kind, error.data) == (Kind.ERROR, b"K\x10")
    assert error.meaning == "incomplete 'K' command: 2 bytes before the end of the trace"


def test_unanswered_q_at_end_leaves_later_bytes_to_the_tracker() -> None:
    chunks = [Chunk(b"Q", Direction.PC), Chunk(b"G", Direction.PC)]
    annotations = annotate(chunks, TRACKER)
    assert [(a.kind, a.meaning) for a in annotations] == [
        (Kind.COMMAND, "Q: request the Sky Commander bus"),
        (Kind.COMMAND, "G: enter GOTO mode"),
        (Kind.NOTE, "no reply to 'Q: request the Sky Commander bus' in the trace"),
    ]
