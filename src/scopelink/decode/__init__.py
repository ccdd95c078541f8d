"""Trace annotation: every command and reply of a byte trace, with its meaning in plain units.

Pure (no I/O): the ``scopelink decode`` command and the dashboard's traffic panel are built on it.

>>> [a.meaning for a in annotate([Chunk(b"V"), Chunk(b"042507#")])]
['get hand control version', 'version 4.37.07']
"""

from __future__ import annotations

from collections.abc import Iterable

from scopelink.decode.model import (
    Annotation,
    Chunk,
    Direction,
    Kind,
    Peer,
    Protocol,
)
from scopelink.decode.session import Session
from scopelink.decode.skytracker_session import SkyTrackerSession
from scopelink.decode.synscan_session import SynScanSession
from scopelink.decode.trace_text import (
    TraceInputError,
    escape_bytes,
    indi_chunk,
    parse_hex,
    parse_trace,
    split_tag,
    unescape,
)

__all__ = [
    "Annotation",
    "Chunk",
    "Direction",
    "Kind",
    "Peer",
    "Protocol",
    "TraceInputError",
    "annotate",
    "escape_bytes",
    "indi_chunk",
    "parse_hex",
    "parse_trace",
    "split_tag",
    "unescape",
]


def _session(protocol: Protocol) -> Session:
    match protocol:
        case Protocol.SYNSCAN:
            return SynScanSession()
        case Protocol.SKYTRACKER:
            return SkyTrackerSession(behind_bus=True)
        case Protocol.SKYCOMMANDER:
            return SkyTrackerSession(behind_bus=False)


def annotate(
    trace: bytes | Iterable[Chunk], protocol: Protocol = Protocol.SYNSCAN
) -> list[Annotation]:
    """Annotate a trace, in time order, sorted by offset.

    ``trace`` is one untagged byte stream, or chunks. A chunk without a direction is read as the
    stream goes: a command, then its reply by the length it expects, then the next command. A
    chunk with a direction goes to that side; replies answer the commands still awaiting one,
    oldest first. Every byte is in exactly one annotation; never raises on any bytes.
    """
    chunks = [Chunk(trace)] if isinstance(trace, bytes) else trace
    session = _session(protocol)
    offset = 0
    for chunk in chunks:
        if chunk.flushes_input:
            session.flush_input(offset)
        for byte in chunk.data:
            direction = chunk.direction
            if direction is None:
                direction = Direction.DEVICE if session.awaiting_reply() else Direction.PC
            if direction is Direction.PC:
                session.from_pc(byte, offset)
            else:
                session.from_device(byte, offset)
            offset += 1
    session.finish(offset)
    return sorted(session.annotations, key=lambda annotation: annotation.offset)
