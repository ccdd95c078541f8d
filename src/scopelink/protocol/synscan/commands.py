"""SynScan commands on the wire: encoding (client side) and length-framed parsing (server side).

A command is framed by the length its first letter implies, never by a terminator: binary payloads
(``W``, ``H``, ``P``, ``K``, ``T``) may hold any byte. A malformed frame is discarded whole, so its
payload bytes are never read as commands."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Final

from scopelink.protocol.synscan import angles
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.events import (
    NEED_DATA,
    MalformedCommand,
    NeedData,
    ServerError,
    UnknownCommand,
)
from scopelink.protocol.synscan.messages import (
    YEAR_BASE,
    AnyCommand,
    CancelGoto,
    DateTime,
    Echo,
    FixedRateSlew,
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
    GotoRaDec,
    IsAligned,
    IsGotoInProgress,
    Location,
    Passthrough,
    SetAxisPosition,
    SetLocation,
    SetTime,
    SetTrackingMode,
    SlowGoto,
    SyncRaDec,
    VariableRateSlew,
    passthrough_command,
    passthrough_payload,
)

FRAME_LENGTHS: Final[dict[int, int]] = {
    **dict.fromkeys(b"EeZztVmJLMpwh", 1),
    **dict.fromkeys(b"KT", 2),
    **dict.fromkeys(b"WH", 9),
    **dict.fromkeys(b"RBS", 10),
    **dict.fromkeys(b"rbs", 18),
    ord("P"): 8,
}
"""Total length in bytes (letter included) of each command, by its first byte."""


def frame_length(first_byte: int) -> int | None:
    """Length of the command that starts with this byte, or None if no command does."""
    return FRAME_LENGTHS.get(first_byte)


# ---------------------------------------------------------------------------------------- encoding


def encode_command(command: AnyCommand) -> bytes:
    """The exact bytes that send ``command`` (positions as uppercase hex, low byte 00 when
    rounded)."""
    match command:
        case GetRaDec(precise):
            return b"e" if precise else b"E"
        case GetAzAlt(precise):
            return b"z" if precise else b"Z"
        case GotoRaDec(ra, dec, precise):
            return (b"r" if precise else b"R") + _encode_pair(ra, dec, precise)
        case SyncRaDec(ra, dec, precise):
            return (b"s" if precise else b"S") + _encode_pair(ra, dec, precise)
        case GotoAzAlt(az, alt, precise):
            return (b"b" if precise else b"B") + _encode_pair(az, alt, precise)
        case GetTrackingMode():
            return b"t"
        case SetTrackingMode(mode):
            return bytes((ord("T"), mode))
        case (
            VariableRateSlew()
            | FixedRateSlew()
            | GetDeviceVersion()
            | SlowGoto()
            | SetAxisPosition()
            | Passthrough()
        ):
            return b"P" + passthrough_payload(command)
        case GetLocation():
            return b"w"
        case SetLocation(location):
            return b"W" + encode_location(location)
        case GetTime():
            return b"h"
        case SetTime(time):
            return b"H" + encode_date_time(time)
        case GetVersion():
            return b"V"
        case GetModel():
            return b"m"
        case Echo(value):
            return bytes((ord("K"), value))
        case IsAligned():
            return b"J"
        case IsGotoInProgress():
            return b"L"
        case CancelGoto():
            return b"M"
        case GetPointingState():
            return b"p"


def _encode_pair(first: int, second: int, precise: bool) -> bytes:
    return angles.format_hex_angle(first, precise) + b"," + angles.format_hex_angle(second, precise)


def encode_location(location: Location) -> bytes:
    """The 8 bytes of a location (``W`` payload, ``w`` reply without ``#``)."""
    return bytes(
        (
            location.lat_degrees,
            location.lat_minutes,
            location.lat_seconds,
            int(location.south),
            location.lon_degrees,
            location.lon_minutes,
            location.lon_seconds,
            int(location.west),
        )
    )


def encode_date_time(time: DateTime) -> bytes:
    """The 8 bytes of a date and time (``H`` payload, ``h`` reply without ``#``)."""
    return bytes(
        (
            time.hour,
            time.minute,
            time.second,
            time.month,
            time.day,
            time.year - YEAR_BASE,
            time.utc_offset_hours & 0xFF,
            int(time.dst),
        )
    )


# ----------------------------------------------------------------------------------------- parsing


@dataclass(frozen=True, slots=True)
class FieldError:
    """Where and why a payload does not parse; ``index`` counts from the start of the bytes
    given."""

    index: int
    reason: str


def decode_location(payload: bytes) -> Location | FieldError:
    """A location from its 8 bytes; the hemisphere flags must be 0 or 1."""
    for index in (3, 7):
        if payload[index] > 1:
            return FieldError(index, f"hemisphere flag must be 0 or 1, got {payload[index]}")
    lat_d, lat_m, lat_s, south, lon_d, lon_m, lon_s, west = payload
    return Location(lat_d, lat_m, lat_s, bool(south), lon_d, lon_m, lon_s, bool(west))


def decode_date_time(payload: bytes) -> DateTime | FieldError:
    """A date and time from its 8 bytes; the DST flag must be 0 or 1."""
    hour, minute, second, month, day, year, zone, dst = payload
    if dst > 1:
        return FieldError(7, f"DST flag must be 0 or 1, got {dst}")
    offset = zone - 0x100 if zone >= 0x80 else zone
    return DateTime(hour, minute, second, month, day, YEAR_BASE + year, offset, bool(dst))


_HEX_PAIR: Final = {
    precise: re.compile(rb"[0-9A-Fa-f]{%d},[0-9A-Fa-f]{%d}" % (width, width))
    for precise, width in ((True, angles.hex_width(True)), (False, angles.hex_width(False)))
}
"""A well-formed pair of each width; anything else goes through the byte-by-byte check."""


def decode_hex_pair(text: bytes, precise: bool) -> tuple[int, int] | FieldError:
    """Two comma-separated hex angles (either case), e.g. ``34AB,12CE`` or ``34AB0500,12CE0500``."""
    width = angles.hex_width(precise)
    if _HEX_PAIR[precise].fullmatch(text):  # the usual case, at C speed
        return int(text[:width], 16), int(text[width + 1 :], 16)
    for index, byte in enumerate(text):
        if index == width:
            if byte != ord(","):
                return FieldError(index, f"expected ',' got {bytes((byte,))!r}")
        elif not angles.is_hex_digit(byte):
            return FieldError(index, f"expected a hex digit, got {bytes((byte,))!r}")
    return int(text[:width], 16), int(text[width + 1 :], 16)


def decode_command_frame(frame: bytes) -> AnyCommand | FieldError:
    """The command in one complete frame (length as `frame_length` says), or where it is
    malformed."""
    letter = chr(frame[0])
    payload = frame[1:]
    match letter:
        case "E" | "e":
            return GetRaDec(precise=letter == "e")
        case "Z" | "z":
            return GetAzAlt(precise=letter == "z")
        case "R" | "r" | "S" | "s" | "B" | "b":
            return _decode_position_command(letter, payload)
        case "t":
            return GetTrackingMode()
        case "T":
            return SetTrackingMode(payload[0])
        case "P":
            return passthrough_command(payload)
        case "w":
            return GetLocation()
        case "W":
            location = decode_location(payload)
            return _shifted(location) if isinstance(location, FieldError) else SetLocation(location)
        case "h":
            return GetTime()
        case "H":
            time = decode_date_time(payload)
            return _shifted(time) if isinstance(time, FieldError) else SetTime(time)
        case "V":
            return GetVersion()
        case "m":
            return GetModel()
        case "K":
            return Echo(payload[0])
        case "J":
            return IsAligned()
        case "L":
            return IsGotoInProgress()
        case "M":
            return CancelGoto()
        case "p":
            return GetPointingState()
    raise ValueError(f"no command starts with {frame[:1]!r}")


def _decode_position_command(letter: str, payload: bytes) -> AnyCommand | FieldError:
    precise = letter.islower()
    pair = decode_hex_pair(payload, precise)
    if isinstance(pair, FieldError):
        return _shifted(pair)
    match letter.upper():
        case "R":
            return GotoRaDec(*pair, precise=precise)
        case "S":
            return SyncRaDec(*pair, precise=precise)
        case _:
            return GotoAzAlt(*pair, precise=precise)


def _shifted(error: FieldError) -> FieldError:
    """A payload error re-indexed from the start of the frame (past the command letter)."""
    return FieldError(error.index + 1, error.reason)


@dataclass(frozen=True, slots=True)
class ParsedCommand:
    """A command with where it was in the stream and its exact bytes."""

    command: AnyCommand
    raw: bytes
    offset: int


class CommandParser:
    """Incremental, length-framed parser of the PC -> hand control byte stream.

    Feed bytes with `receive_data`; `next_frame` (or `next_event`) returns one command or error at a
    time, or `NEED_DATA`. A stray ``#`` between commands is skipped silently; an unknown byte gives
    `UnknownCommand` and is skipped; a malformed payload gives `MalformedCommand` and its whole
    frame is discarded. Never raises on any input."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._offset = 0

    @property
    def offset(self) -> int:
        """Stream offset of the first byte not yet consumed."""
        return self._offset

    @property
    def pending(self) -> bytes:
        """Bytes received but not yet consumed (the start of an incomplete frame)."""
        return bytes(self._buffer)

    def receive_data(self, data: bytes) -> None:
        """Append bytes read from the link."""
        self._buffer += data

    def next_frame(self) -> ParsedCommand | ServerError | NeedData:
        """The next command with its offset and raw bytes, an error event, or `NEED_DATA`."""
        while self._buffer and self._buffer[0] == HASH:
            self._consume(1)
        if not self._buffer:
            return NEED_DATA
        offset = self._offset
        length = frame_length(self._buffer[0])
        if length is None:
            return UnknownCommand(self._consume(1)[0], offset)
        if len(self._buffer) < length:
            return NEED_DATA
        frame = self._consume(length)
        parsed = decode_command_frame(frame)
        if isinstance(parsed, FieldError):
            return MalformedCommand(frame, parsed.index, offset, parsed.reason)
        return ParsedCommand(parsed, frame, offset)

    def next_event(self) -> AnyCommand | ServerError | NeedData:
        """The next command, an error event, or `NEED_DATA`."""
        event = self.next_frame()
        return event.command if isinstance(event, ParsedCommand) else event

    def discard_partial(self) -> bytes:
        """Drop and return an incomplete frame (call after an inter-byte timeout)."""
        return self._consume(len(self._buffer))

    def _consume(self, count: int) -> bytes:
        taken = bytes(self._buffer[:count])
        del self._buffer[:count]
        self._offset += count
        return taken
