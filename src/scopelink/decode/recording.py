"""Recorded sessions: every byte each way with its time, as JSON lines (docs/cli.md, "Record").

The format, version 1 (``scopelink record`` writes it; ``scopelink decode`` and
``scopelink emulate ... --replay`` read it)::

    {"scopelink_recording": 1, "protocol": "synscan", "device": "synscan:/dev/ttyUSB0", ...}
    {"t": 0.000812, "dir": "->", "data": "e"}
    {"t": 0.021337, "dir": "<-", "data": "34AB0500,12CE0500#"}

The first line is the header: the format version, the protocol (``synscan``, ``skytracker``,
``skycommander`` or null when the device was not named), and free descriptive keys. Every other
line is one transfer as one read returned it: ``t`` seconds since the recording started,
``dir`` ``->`` from the computer or ``<-`` from the device, ``data`` the bytes as escaped text
(:func:`scopelink.decode.escape_bytes`). Pure: no I/O here.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Final

from scopelink.decode.model import Chunk, Direction, Protocol
from scopelink.decode.trace_text import TraceInputError, escape_bytes, unescape

__all__ = [
    "RECORDING_KEY",
    "RECORDING_VERSION",
    "Exchange",
    "Recording",
    "RecordingError",
    "Transfer",
    "event_line",
    "header_line",
    "is_recording",
    "read_recording",
]

RECORDING_KEY: Final = "scopelink_recording"
RECORDING_VERSION: Final = 1
_ARROWS: Final = {Direction.PC: "->", Direction.DEVICE: "<-"}
_DIRECTIONS: Final = {arrow: direction for direction, arrow in _ARROWS.items()}


class RecordingError(ValueError):
    """A file that is not a readable recording; the message names the line."""


@dataclass(frozen=True, slots=True)
class Transfer:
    """Bytes one read returned, ``t`` seconds after the recording started."""

    t: float
    direction: Direction
    data: bytes
    line: int
    """Line number in the file (1 is the header)."""


@dataclass(frozen=True, slots=True)
class Exchange:
    """What the computer sent, then what the device answered before the computer spoke again."""

    command: bytes
    reply: bytes
    line: int
    """The file line of the command's first transfer (or of the reply, for a leading reply)."""


@dataclass(frozen=True, slots=True)
class Recording:
    header: dict[str, Any]
    transfers: tuple[Transfer, ...] = field(default=())

    @property
    def protocol(self) -> Protocol | None:
        name = self.header.get("protocol")
        return Protocol(name) if name else None

    def chunks(self) -> list[Chunk]:
        """The transfers as tagged chunks, for :func:`scopelink.decode.annotate`."""
        return [Chunk(transfer.data, transfer.direction) for transfer in self.transfers]

    def exchanges(self) -> list[Exchange]:
        """Consecutive transfers of one direction joined: each command with the reply after it."""
        exchanges: list[Exchange] = []
        command, reply, line = bytearray(), bytearray(), 0
        for transfer in self.transfers:
            if transfer.direction is Direction.PC:
                if reply:
                    exchanges.append(Exchange(bytes(command), bytes(reply), line))
                    command, reply = bytearray(), bytearray()
                if not command:
                    line = transfer.line
                command += transfer.data
            else:
                if not command and not reply:
                    line = transfer.line
                reply += transfer.data
        if command or reply:
            exchanges.append(Exchange(bytes(command), bytes(reply), line))
        return exchanges


def header_line(protocol: Protocol | None, **about: object) -> str:
    """The first line of a recording (no newline)."""
    header = {RECORDING_KEY: RECORDING_VERSION, "protocol": protocol.value if protocol else None}
    return json.dumps({**header, **about}, ensure_ascii=False)


def event_line(t: float, direction: Direction, data: bytes) -> str:
    """One transfer as a line (no newline)."""
    return json.dumps({"t": round(t, 6), "dir": _ARROWS[direction], "data": escape_bytes(data)})


def is_recording(text: bytes) -> bool:
    """Whether ``text`` starts with a recording's header line."""
    return text.lstrip()[: len(RECORDING_KEY) + 3].startswith(b'{"' + RECORDING_KEY.encode())


def read_recording(text: bytes) -> Recording:
    """The recording in ``text``; :class:`RecordingError` names the first line it cannot read."""
    lines = text.splitlines()
    if not lines or not is_recording(lines[0]):
        raise RecordingError(f"line 1: not a scopelink recording (no {RECORDING_KEY!r} header)")
    header = _object(lines[0], 1)
    version = header.get(RECORDING_KEY)
    if version != RECORDING_VERSION:
        raise RecordingError(
            f"line 1: recording format version {version!r}; this scopelink reads version "
            f"{RECORDING_VERSION} (a newer scopelink wrote it?)"
        )
    protocol = header.get("protocol")
    if protocol is not None and protocol not in {p.value for p in Protocol}:
        raise RecordingError(f"line 1: unknown protocol {protocol!r}")
    transfers: list[Transfer] = []
    previous = 0.0
    for number, raw in enumerate(lines[1:], start=2):
        if not raw.strip():
            continue
        event = _object(raw, number)
        t, arrow, data = event.get("t"), event.get("dir"), event.get("data")
        if not isinstance(t, int | float) or isinstance(t, bool) or not t >= previous:
            reason = f"'t' must be seconds, not before {previous}"
            raise RecordingError(f"line {number}: {reason}")
        if arrow not in _DIRECTIONS:
            raise RecordingError(f"line {number}: 'dir' must be '->' or '<-', not {arrow!r}")
        if not isinstance(data, str) or not data:
            raise RecordingError(f"line {number}: 'data' must be escaped bytes")
        try:
            payload = unescape(data.encode("latin-1"))
        except (TraceInputError, UnicodeEncodeError) as error:
            raise RecordingError(f"line {number}: 'data': {error}") from None
        transfers.append(Transfer(float(t), _DIRECTIONS[arrow], payload, number))
        previous = float(t)
    return Recording(header, tuple(transfers))


def _object(raw: bytes, number: int) -> dict[str, Any]:
    try:
        value = json.loads(raw)
    except ValueError as error:
        raise RecordingError(f"line {number}: not JSON ({error})") from None
    if not isinstance(value, dict):
        raise RecordingError(f"line {number}: not a JSON object")
    return value
