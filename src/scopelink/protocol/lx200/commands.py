"""LX200 commands as typed values: the subset SkySafari, Stellarium and INDI's LX200 drivers use.

A command is ``:`` + code + optional argument + ``#``; the ACK byte 0x06 stands alone.
:func:`parse_command` turns the text between ``:`` and ``#`` into a command, an
:class:`UnknownCommand` (not in our set: a real handset ignores it, and so do we) or a
:class:`MalformedCommand` (a known code with an argument that does not parse or is out of range).
:func:`encode_command` writes a command the way a client does (no space after the code; the
parser accepts one, as INDI sends it).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from dataclasses import dataclass, field

from scopelink.protocol.base import Event
from scopelink.protocol.lx200.angles import (
    ASTERISK_DEGREE_SIGN,
    degree_sign_of,
    format_dec,
    format_ra,
    format_signed_degrees_minutes,
    parse_sexagesimal,
    precision_of,
)

__all__ = [
    "ACK_BYTE",
    "Ack",
    "AnyCommand",
    "Direction",
    "Get",
    "GotoTarget",
    "Halt",
    "MalformedCommand",
    "Move",
    "PulseGuide",
    "Query",
    "ReplyKind",
    "SetLatitude",
    "SetLocalDate",
    "SetLocalTime",
    "SetLongitude",
    "SetRate",
    "SetTargetDec",
    "SetTargetRA",
    "SetUtcOffset",
    "SlewRate",
    "SyncTarget",
    "TogglePrecision",
    "UnknownCommand",
    "encode_command",
    "parse_command",
    "reply_kind",
]

ACK_BYTE = 0x06


class Query(enum.Enum):
    """Commands that only read something; the value is the wire code."""

    RA = "GR"
    DEC = "GD"
    ALTITUDE = "GA"
    AZIMUTH = "GZ"
    SIDEREAL_TIME = "GS"
    LOCAL_TIME = "GL"
    LOCAL_TIME_12H = "Ga"
    DATE = "GC"
    LATITUDE = "Gt"
    LONGITUDE = "Gg"
    UTC_OFFSET = "GG"
    TIME_FORMAT = "Gc"
    TRACKING_RATE = "GT"
    SITE_1_NAME = "GM"
    SITE_2_NAME = "GN"
    SITE_3_NAME = "GO"
    SITE_4_NAME = "GP"
    TARGET_RA = "Gr"
    TARGET_DEC = "Gd"
    PRODUCT = "GVP"
    FIRMWARE_NUMBER = "GVN"
    FIRMWARE_DATE = "GVD"
    FIRMWARE_TIME = "GVT"
    FIRMWARE_FULL = "GVF"
    STATUS = "GW"
    DISTANCE_BARS = "D"


class Direction(enum.Enum):
    NORTH = "n"
    SOUTH = "s"
    EAST = "e"
    WEST = "w"


class SlewRate(enum.Enum):
    """The four rates of ``:RG# :RC# :RM# :RS#`` (guide, centre, find, slew)."""

    GUIDE = "G"
    CENTER = "C"
    FIND = "M"
    SLEW = "S"


@dataclass(frozen=True, slots=True)
class Ack:
    """The single byte 0x06: the handset answers its alignment mode with one letter."""


@dataclass(frozen=True, slots=True)
class Get:
    what: Query


@dataclass(frozen=True, slots=True)
class TogglePrecision:
    """``:U#``: toggle between low and high precision coordinates (no reply)."""


@dataclass(frozen=True, slots=True)
class SetTargetRA:
    """``:Sr HH:MM:SS#`` (or ``HH:MM.T``): the target's right ascension (of date).

    ``high_precision``: the form the client wrote (True with seconds, False without), not part
    of the command's meaning."""

    ra_hours: float
    high_precision: bool | None = field(default=None, compare=False)


@dataclass(frozen=True, slots=True)
class SetTargetDec:
    """``:Sd sDD*MM:SS#`` (or ``sDD*MM``): the target's declination (of date).

    ``degree_sign``: the one the client wrote (0xDF or ``*``), None for another separator; not
    part of the command's meaning (two ``:Sd`` that differ only in it are equal)."""

    dec_deg: float
    degree_sign: str | None = field(default=None, compare=False)
    high_precision: bool | None = field(default=None, compare=False)
    """The form the client wrote: True with seconds, False without."""


@dataclass(frozen=True, slots=True)
class GotoTarget:
    """``:MS#``: slew to the target; replies ``0`` or ``1``/``2`` with a reason and ``#``."""


@dataclass(frozen=True, slots=True)
class SyncTarget:
    """``:CM#`` (or ``:CR#``): the mount points at the target now."""

    code: str = "CM"


@dataclass(frozen=True, slots=True)
class Halt:
    """``:Q#`` (``direction`` None: stop every motion, slews included) or ``:Qn# :Qs# ...``."""

    direction: Direction | None = None


@dataclass(frozen=True, slots=True)
class Move:
    """``:Mn# :Ms# :Me# :Mw#``: move at the current rate until halted."""

    direction: Direction


@dataclass(frozen=True, slots=True)
class PulseGuide:
    """``:MgnDDDD#``: move at the guide rate for ``duration_ms`` milliseconds."""

    direction: Direction
    duration_ms: int


@dataclass(frozen=True, slots=True)
class SetRate:
    rate: SlewRate


@dataclass(frozen=True, slots=True)
class SetLatitude:
    """``:St sDD*MM#`` (or with seconds): the site latitude, north positive.

    ``degree_sign``: the one the client wrote (0xDF or ``*``), None for another separator; not
    part of the command's meaning (two ``:Sd`` that differ only in it are equal)."""

    latitude_deg: float
    degree_sign: str | None = field(default=None, compare=False)


@dataclass(frozen=True, slots=True)
class SetLongitude:
    """``:Sg DDD*MM#``: the site longitude as Meade counts it, **west** positive, 0..360."""

    west_longitude_deg: float
    degree_sign: str | None = field(default=None, compare=False)
    """The one the client wrote (0xDF or ``*``), None for another separator."""

    @property
    def east_longitude_deg(self) -> float:
        """East positive in (-180, 180], as :class:`~scopelink.astro.Site` wants it."""
        east = -self.west_longitude_deg % 360.0
        return east - 360.0 if east > 180.0 else east


@dataclass(frozen=True, slots=True)
class SetUtcOffset:
    """``:SG sHH.H#``: hours to **add to local time** to get UTC (so UTC+2 is sent as -02)."""

    hours: float


@dataclass(frozen=True, slots=True)
class SetLocalTime:
    """``:SL HH:MM:SS#``: the local time of day (24 h)."""

    hour: int
    minute: int
    second: int


@dataclass(frozen=True, slots=True)
class SetLocalDate:
    """``:SC MM/DD/YY#``: the local date; the reply is ``1`` and two ``#`` strings."""

    month: int
    day: int
    year: int
    """Full year: two-digit years are 2000-2099 (Meade's handsets count from 2000 too)."""


@dataclass(frozen=True, slots=True)
class UnknownCommand(Event):
    """A ``:...#`` command outside our set; a real handset ignores it, so we do too."""

    text: str

    def describe(self) -> str:
        return f"unknown command :{self.text}#, ignored"


@dataclass(frozen=True, slots=True)
class MalformedCommand(Event):
    """A known command whose argument is missing, does not parse or is out of range."""

    code: str
    text: str
    reason: str

    def describe(self) -> str:
        return f"malformed command :{self.text}#: {self.reason}"


AnyCommand = (
    Ack
    | Get
    | TogglePrecision
    | SetTargetRA
    | SetTargetDec
    | GotoTarget
    | SyncTarget
    | Halt
    | Move
    | PulseGuide
    | SetRate
    | SetLatitude
    | SetLongitude
    | SetUtcOffset
    | SetLocalTime
    | SetLocalDate
)


class ReplyKind(enum.Enum):
    """The shape of a command's reply, which a client reads by."""

    NONE = "none"
    CHAR = "one character"  # ACK's letter, and '1'/'0' of the set commands
    TERMINATED = "text up to '#'"
    SLEW = "'0', or '1'/'2' + text + '#'"
    DATE_SET = "'1' + two '#' strings, or '0'"


def reply_kind(command: AnyCommand | MalformedCommand) -> ReplyKind:
    """How the reply to ``command`` is shaped (a malformed set command still gets its '0')."""
    if isinstance(command, MalformedCommand):
        return ReplyKind.CHAR if command.code in _BOOLEAN_CODES else ReplyKind.NONE
    if isinstance(command, Get | SyncTarget):
        return ReplyKind.TERMINATED
    if isinstance(command, GotoTarget):
        return ReplyKind.SLEW
    if isinstance(command, SetLocalDate):
        return ReplyKind.DATE_SET
    if isinstance(
        command,
        Ack | SetTargetRA | SetTargetDec | SetLatitude | SetLongitude | SetUtcOffset | SetLocalTime,
    ):
        return ReplyKind.CHAR
    return ReplyKind.NONE


_BOOLEAN_CODES = frozenset({"Sr", "Sd", "St", "Sg", "SG", "SL", "SC"})
_QUERIES = {query.value: query for query in Query}
_DIRECTIONS = {direction.value: direction for direction in Direction}
_RATES = {rate.value: rate for rate in SlewRate}


def parse_command(text: str) -> AnyCommand | UnknownCommand | MalformedCommand:
    """The command whose text (between ``:`` and ``#``) is ``text``; never raises."""
    if text in _QUERIES:
        return Get(_QUERIES[text])
    if text == "U":
        return TogglePrecision()
    if text == "MS":
        return GotoTarget()
    if text in ("CM", "CR"):
        return SyncTarget(text)
    if text == "Q":
        return Halt()
    if len(text) == 2 and text[0] == "Q" and text[1] in _DIRECTIONS:
        return Halt(_DIRECTIONS[text[1]])
    if len(text) == 2 and text[0] == "M" and text[1] in _DIRECTIONS:
        return Move(_DIRECTIONS[text[1]])
    if len(text) == 2 and text[0] == "R" and text[1] in _RATES:
        return SetRate(_RATES[text[1]])
    if text.startswith("Mg") and len(text) >= 3 and text[2] in _DIRECTIONS:
        return _pulse(text)
    code, argument = text[:2], text[2:]
    parser = _SETTERS.get(code)
    if parser is None:
        return UnknownCommand(text)
    try:
        return parser(argument.strip())
    except ValueError as exc:
        return MalformedCommand(code, text, str(exc))


def _pulse(text: str) -> PulseGuide | MalformedCommand:
    digits = text[3:]
    if not (digits.isascii() and digits.isdigit() and len(digits) <= 5):
        return MalformedCommand("Mg", text, "the duration must be up to 5 digits of milliseconds")
    return PulseGuide(_DIRECTIONS[text[2]], int(digits))


def _angle(argument: str, what: str, low: float, high: float) -> float:
    value = parse_sexagesimal(argument)
    if value is None:
        raise ValueError(f"{what} {argument!r} is not a sexagesimal number")
    if not low <= value <= high:
        raise ValueError(f"{what} {argument!r} lies outside [{low:g}, {high:g}]")
    return value


def _set_ra(argument: str) -> SetTargetRA:
    if argument.startswith(("-", "+")):
        raise ValueError(f"right ascension {argument!r} carries a sign")
    value = _angle(argument, "right ascension", 0.0, 24.0)
    if value >= 24.0:
        raise ValueError(f"right ascension {argument!r} must lie below 24 h")
    return SetTargetRA(value, precision_of(argument))


def _set_dec(argument: str) -> SetTargetDec:
    value = _angle(argument, "declination", -90.0, 90.0)
    return SetTargetDec(value, degree_sign_of(argument), precision_of(argument))


def _set_latitude(argument: str) -> SetLatitude:
    return SetLatitude(_angle(argument, "latitude", -90.0, 90.0), degree_sign_of(argument))


def _set_longitude(argument: str) -> SetLongitude:
    value = _angle(argument, "longitude", -360.0, 360.0)
    return SetLongitude(value, degree_sign_of(argument))


def _set_utc_offset(argument: str) -> SetUtcOffset:
    try:
        hours = float(argument)
    except ValueError:
        raise ValueError(f"UTC offset {argument!r} is not a number of hours") from None
    if not (math.isfinite(hours) and -14.0 <= hours <= 14.0):
        raise ValueError(f"UTC offset {argument!r} lies outside [-14, 14] hours")
    return SetUtcOffset(hours)


def _numbers(argument: str, separator: str, what: str) -> tuple[int, int, int]:
    parts = argument.split(separator)
    if len(parts) != 3 or not all(p.isascii() and p.isdigit() and len(p) <= 2 for p in parts):
        raise ValueError(f"{what} {argument!r} must read NN{separator}NN{separator}NN")
    first, second, third = (int(p) for p in parts)
    return first, second, third


def _set_local_time(argument: str) -> SetLocalTime:
    hour, minute, second = _numbers(argument, ":", "time")
    if hour > 23 or minute > 59 or second > 59:
        raise ValueError(f"time {argument!r} is not a time of day")
    return SetLocalTime(hour, minute, second)


def _set_local_date(argument: str) -> SetLocalDate:
    month, day, year = _numbers(argument, "/", "date")
    if not (1 <= month <= 12 and 1 <= day <= _days_in(month, 2000 + year)):
        raise ValueError(f"date {argument!r} is not a date (MM/DD/YY)")
    return SetLocalDate(month, day, 2000 + year)


def _days_in(month: int, year: int) -> int:
    if month == 2:
        return 29 if year % 4 == 0 and (year % 100 != 0 or year % 400 == 0) else 28
    return 30 if month in (4, 6, 9, 11) else 31


_SETTERS: dict[str, Callable[[str], AnyCommand]] = {
    "Sr": _set_ra,
    "Sd": _set_dec,
    "St": _set_latitude,
    "Sg": _set_longitude,
    "SG": _set_utc_offset,
    "SL": _set_local_time,
    "SC": _set_local_date,
}


def encode_command(command: AnyCommand, *, high_precision: bool = True) -> bytes:
    """The bytes a client sends for ``command``: the degree sign the command carries, else
    ``*`` as SkySafari writes it (ASCII; the handset's replies use Meade's 0xDF)."""
    if isinstance(command, Ack):
        return bytes([ACK_BYTE])
    return f":{_command_text(command, high_precision)}#".encode("latin-1")


def _command_text(command: AnyCommand, high_precision: bool) -> str:
    match command:
        case Get(what):
            return what.value
        case TogglePrecision():
            return "U"
        case SetTargetRA(ra):
            return "Sr" + format_ra(ra, high_precision=high_precision)
        case SetTargetDec(dec, sign):
            return "Sd" + format_dec(
                dec, high_precision=high_precision, degree_sign=sign or ASTERISK_DEGREE_SIGN
            )
        case GotoTarget():
            return "MS"
        case SyncTarget(code):
            return code
        case Halt(direction):
            return "Q" + (direction.value if direction else "")
        case Move(direction):
            return "M" + direction.value
        case PulseGuide(direction, duration):
            return f"Mg{direction.value}{duration:04d}"
        case SetRate(rate):
            return "R" + rate.value
        case SetLatitude(latitude, sign):
            degree = sign or ASTERISK_DEGREE_SIGN
            return "St" + format_signed_degrees_minutes(latitude, degree_sign=degree)
        case SetLongitude(west, degree):
            total = round(abs(west) * 60.0)
            sign = "-" if west < 0 and total else ""
            return f"Sg{sign}{total // 60:03d}{degree or ASTERISK_DEGREE_SIGN}{total % 60:02d}"
        case SetUtcOffset(hours):
            return f"SG{hours:+05.1f}"
        case SetLocalTime(hour, minute, second):
            return f"SL{hour:02d}:{minute:02d}:{second:02d}"
        case SetLocalDate(month, day, year):
            return f"SC{month:02d}/{day:02d}/{year % 100:02d}"
        case Ack():  # pragma: no cover - encoded as the bare byte above
            return ""
