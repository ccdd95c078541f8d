"""Typed SynScan commands and replies.

Every message stores the wire's integer units exactly, so encoding and parsing round-trip bit for
bit, and offers plain units (hours, degrees, arcsec/s) as properties and ``from_...`` constructors.
``describe()`` (also ``str()``) says what a message means in plain units."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from enum import Enum, IntEnum, StrEnum
from typing import ClassVar, Self

from scopelink.protocol.synscan import angles
from scopelink.protocol.synscan.angles import HASH


class Message:
    """Base of every SynScan command and reply."""

    __slots__ = ()

    def describe(self) -> str:
        """What the message means, in plain units."""
        raise NotImplementedError

    def __str__(self) -> str:
        return self.describe()


class Command(Message):
    """A message from the PC to the hand control."""

    __slots__ = ()


class Reply(Message):
    """A message from the hand control to the PC."""

    __slots__ = ()


def _check_range(name: str, value: int, low: int, high: int) -> None:
    if not low <= value <= high:
        raise ValueError(f"{name} must be in {low}..{high}, got {value}")


def _check_byte(name: str, value: int) -> None:
    _check_range(name, value, 0, 0xFF)


def _check_units(name: str, units: int, precise: bool) -> None:
    _check_range(name, units, 0, angles.units_per_revolution(precise) - 1)


def _precision_word(precise: bool) -> str:
    return "precise " if precise else ""


class Axis(IntEnum):
    """Motor controller addresses used by the passthrough commands."""

    AZM_RA = 16
    ALT_DEC = 17

    @property
    def label(self) -> str:
        """Human name of the axis."""
        return "RA/Azm" if self is Axis.AZM_RA else "Dec/Alt"


class Frame(Enum):
    """Which pair of coordinates a position carries."""

    EQUATORIAL = "RA/Dec"
    HORIZONTAL = "Az/Alt"


class Tracking(IntEnum):
    """SynScan tracking modes (``t``/``T``)."""

    OFF = 0
    ALT_AZ = 1
    EQUATORIAL = 2
    PEC = 3


_TRACKING_NAMES: dict[int, str] = {
    Tracking.OFF: "off",
    Tracking.ALT_AZ: "alt-az",
    Tracking.EQUATORIAL: "equatorial",
    Tracking.PEC: "equatorial with PEC",
}


def _describe_tracking(mode: int) -> str:
    return f"{mode} ({_TRACKING_NAMES.get(mode, 'unknown')})"


def _describe_ra_dec(ra_units: int, dec_units: int, precise: bool) -> str:
    ra_hours = angles.degrees_to_hours(angles.units_to_degrees(ra_units, precise))
    dec, flipped = angles.fold_over_pole(angles.units_to_signed_degrees(dec_units, precise))
    pole = " (over the pole)" if flipped else ""
    return f"RA {angles.format_hours(ra_hours)}, Dec {angles.format_signed_degrees(dec)}{pole}"


def _describe_az_alt(az_units: int, alt_units: int, precise: bool) -> str:
    az = angles.units_to_degrees(az_units, precise)
    alt, flipped = angles.fold_over_pole(angles.units_to_signed_degrees(alt_units, precise))
    over = " (over the zenith)" if flipped else ""
    return f"Az {angles.format_degrees(az)}, Alt {angles.format_signed_degrees(alt)}{over}"


# ---------------------------------------------------------------------------------------- commands


@dataclass(frozen=True, slots=True)
class GetRaDec(Command):
    """``E`` (or ``e`` when precise): read RA/Dec (J2000)."""

    precise: bool = True

    def describe(self) -> str:
        return f"get {_precision_word(self.precise)}RA/Dec"


@dataclass(frozen=True, slots=True)
class GetAzAlt(Command):
    """``Z`` (or ``z`` when precise): read Az/Alt."""

    precise: bool = True

    def describe(self) -> str:
        return f"get {_precision_word(self.precise)}Az/Alt"


@dataclass(frozen=True, slots=True)
class _RaDecTarget(Command):
    """Shared shape of goto and sync on RA/Dec (J2000). Units as on the wire."""

    ra_units: int
    dec_units: int
    precise: bool = True

    _VERB: ClassVar[str] = ""

    def __post_init__(self) -> None:
        _check_units("ra_units", self.ra_units, self.precise)
        _check_units("dec_units", self.dec_units, self.precise)

    @classmethod
    def from_hours_degrees(cls, ra_hours: float, dec_degrees: float, precise: bool = True) -> Self:
        """From RA in hours and Dec in degrees (negative Dec becomes the two's complement)."""
        return cls(*_ra_dec_units(ra_hours, dec_degrees, precise), precise)

    @property
    def ra_hours(self) -> float:
        """Right ascension in hours, [0, 24)."""
        return angles.degrees_to_hours(angles.units_to_degrees(self.ra_units, self.precise))

    @property
    def dec_degrees(self) -> float:
        """Declination in degrees, two's complement read: [-180, 180)."""
        return angles.units_to_signed_degrees(self.dec_units, self.precise)

    def describe(self) -> str:
        detail = _describe_ra_dec(self.ra_units, self.dec_units, self.precise)
        return f"{_precision_word(self.precise)}{self._VERB} {detail}"


class GotoRaDec(_RaDecTarget):
    """``R`` (or ``r`` when precise): goto RA/Dec (J2000)."""

    __slots__ = ()
    _VERB = "goto"


class SyncRaDec(_RaDecTarget):
    """``S`` (or ``s`` when precise): sync on RA/Dec (J2000)."""

    __slots__ = ()
    _VERB = "sync"


def _ra_dec_units(ra_hours: float, dec_degrees: float, precise: bool) -> tuple[int, int]:
    return (
        angles.degrees_to_units(angles.hours_to_degrees(ra_hours), precise),
        angles.degrees_to_units(dec_degrees, precise),
    )


@dataclass(frozen=True, slots=True)
class GotoAzAlt(Command):
    """``B`` (or ``b`` when precise): goto Az/Alt. Units as on the wire."""

    az_units: int
    alt_units: int
    precise: bool = True

    def __post_init__(self) -> None:
        _check_units("az_units", self.az_units, self.precise)
        _check_units("alt_units", self.alt_units, self.precise)

    @classmethod
    def from_degrees(cls, az_degrees: float, alt_degrees: float, precise: bool = True) -> GotoAzAlt:
        """Goto azimuth and altitude in degrees."""
        return cls(
            angles.degrees_to_units(az_degrees, precise),
            angles.degrees_to_units(alt_degrees, precise),
            precise,
        )

    @property
    def az_degrees(self) -> float:
        """Azimuth in degrees, [0, 360)."""
        return angles.units_to_degrees(self.az_units, self.precise)

    @property
    def alt_degrees(self) -> float:
        """Altitude in degrees, two's complement read: [-180, 180)."""
        return angles.units_to_signed_degrees(self.alt_units, self.precise)

    def describe(self) -> str:
        detail = _describe_az_alt(self.az_units, self.alt_units, self.precise)
        return f"{_precision_word(self.precise)}goto {detail}"


@dataclass(frozen=True, slots=True)
class GetTrackingMode(Command):
    """``t``: read the tracking mode."""

    def describe(self) -> str:
        return "get tracking mode"


@dataclass(frozen=True, slots=True)
class SetTrackingMode(Command):
    """``T`` + mode byte: set the tracking mode (see `Tracking`)."""

    mode: int

    def __post_init__(self) -> None:
        _check_byte("mode", self.mode)

    def describe(self) -> str:
        return f"set tracking mode {_describe_tracking(self.mode)}"


@dataclass(frozen=True, slots=True)
class VariableRateSlew(Command):
    """``P 3 axis 6|7 hi lo 0 0``: slew one axis at a variable rate (quarter arcsec/s units)."""

    axis: Axis
    positive: bool
    rate_units: int

    def __post_init__(self) -> None:
        _check_range("rate_units", self.rate_units, 0, angles.MAX_RATE_UNITS)

    @classmethod
    def from_arcsec_per_second(cls, axis: Axis, arcsec_per_second: float) -> VariableRateSlew:
        """Slew at a signed rate in arcsec/s; the sign picks the direction."""
        return cls(axis, arcsec_per_second >= 0, angles.rate_to_units(arcsec_per_second))

    @property
    def arcsec_per_second(self) -> float:
        """Signed rate in arcsec/s (negative for the negative direction)."""
        rate = angles.units_to_rate(self.rate_units)
        return rate if self.positive else -rate

    def describe(self) -> str:
        sign = "+" if self.positive else "-"
        rate = angles.units_to_rate(self.rate_units)
        return f"slew {self.axis.label} {sign} at {rate:.2f} arcsec/s (variable rate)"


@dataclass(frozen=True, slots=True)
class FixedRateSlew(Command):
    """``P 2 axis 36|37 rate 0 0 0``: slew one axis at a hand-control speed 1-9; 0 stops."""

    axis: Axis
    positive: bool
    rate: int

    def __post_init__(self) -> None:
        _check_range("rate", self.rate, 0, 9)

    def describe(self) -> str:
        if self.rate == 0:
            return f"stop {self.axis.label} (fixed rate 0)"
        sign = "+" if self.positive else "-"
        return f"slew {self.axis.label} {sign} at fixed rate {self.rate}"


@dataclass(frozen=True, slots=True)
class GetDeviceVersion(Command):
    """``P 1 axis 254 0 0 0 2``: read a motor controller's firmware version."""

    axis: Axis

    def describe(self) -> str:
        return f"get {self.axis.label} motor controller version"


@dataclass(frozen=True, slots=True)
class _AxisPositionCommand(Command):
    """Shared shape of the passthrough commands that carry one 24-bit axis position."""

    axis: Axis
    position: int

    _VERB: ClassVar[str] = ""

    def __post_init__(self) -> None:
        _check_range("position", self.position, 0, angles.POSITION24_UNITS - 1)

    @classmethod
    def from_degrees(cls, axis: Axis, degrees: float) -> Self:
        """From an axis angle in degrees (wrapped, rounded to the 24-bit step)."""
        return cls(axis, angles.degrees_to_position24(degrees))

    @property
    def degrees(self) -> float:
        """The axis angle in degrees, [0, 360)."""
        return angles.position24_to_degrees(self.position)

    def describe(self) -> str:
        return f"{self._VERB} {self.axis.label} to {self.degrees:.4f}°"


class SlowGoto(_AxisPositionCommand):
    """``P 4 axis 23 h m l 0``: slow goto of one axis to a 24-bit position."""

    __slots__ = ()
    _VERB = "slow goto"


class SetAxisPosition(_AxisPositionCommand):
    """``P 4 axis 4 h m l 0``: redefine one axis's current position (24-bit)."""

    __slots__ = ()
    _VERB = "set position of"


PASSTHROUGH_PAYLOAD_LENGTH = 7


@dataclass(frozen=True, slots=True)
class Passthrough(Command):
    """``P`` + any other 7-byte payload; its last byte is the number of reply bytes before ``#``.

    Payloads that have a typed command are refused: use `passthrough_command` to get whichever fits.
    """

    payload: bytes

    def __post_init__(self) -> None:
        if len(self.payload) != PASSTHROUGH_PAYLOAD_LENGTH:
            raise ValueError(
                f"a passthrough payload is {PASSTHROUGH_PAYLOAD_LENGTH} bytes,"
                f" got {len(self.payload)}"
            )
        typed = _typed_passthrough(self.payload)
        if typed is not None:
            raise ValueError(f"payload {self.payload.hex(' ')} is {type(typed).__name__}; use that")

    @property
    def reply_length(self) -> int:
        """Number of reply bytes before the ``#``."""
        return self.payload[-1]

    def describe(self) -> str:
        return f"passthrough {self.payload.hex(' ').upper()} (reply {self.reply_length} bytes)"


_VARIABLE_SLEW_LENGTH = 3
_FIXED_SLEW_LENGTH = 2
_VERSION_QUERY_LENGTH = 1
_POSITION_LENGTH = 4
_POSITIVE_VARIABLE, _NEGATIVE_VARIABLE = 6, 7
_POSITIVE_FIXED, _NEGATIVE_FIXED = 36, 37
_GET_VERSION = 254
_SLOW_GOTO, _SET_POSITION = 23, 4
_DEVICE_VERSION_REPLY_LENGTH = 2


def passthrough_payload(command: PassthroughCommand) -> bytes:
    """The 7 bytes after ``P`` for any passthrough command."""
    match command:
        case VariableRateSlew(axis, positive, rate_units):
            high, low = angles.rate_units_to_bytes(rate_units)
            direction = _POSITIVE_VARIABLE if positive else _NEGATIVE_VARIABLE
            return bytes((_VARIABLE_SLEW_LENGTH, axis, direction, high, low, 0, 0))
        case FixedRateSlew(axis, positive, rate):
            direction = _POSITIVE_FIXED if positive else _NEGATIVE_FIXED
            return bytes((_FIXED_SLEW_LENGTH, axis, direction, rate, 0, 0, 0))
        case GetDeviceVersion(axis):
            return bytes((_VERSION_QUERY_LENGTH, axis, _GET_VERSION, 0, 0, 0, 2))
        case SlowGoto(axis, position):
            return bytes(
                (_POSITION_LENGTH, axis, _SLOW_GOTO, *angles.position24_to_bytes(position), 0)
            )
        case SetAxisPosition(axis, position):
            return bytes(
                (_POSITION_LENGTH, axis, _SET_POSITION, *angles.position24_to_bytes(position), 0)
            )
        case Passthrough(payload):
            return payload


def passthrough_reply_length(command: PassthroughCommand) -> int:
    """Number of reply bytes before ``#`` that a passthrough command asks for (its 8th byte)."""
    return passthrough_payload(command)[-1]


def passthrough_command(payload: bytes) -> PassthroughCommand:
    """The typed command for a 7-byte ``P`` payload, or `Passthrough` when none fits."""
    typed = _typed_passthrough(payload)
    return Passthrough(payload) if typed is None else typed


def _typed_passthrough(payload: bytes) -> PassthroughCommand | None:
    length, address, code, data1, data2, data3, reply_length = payload
    if address not in (Axis.AZM_RA, Axis.ALT_DEC):
        return None
    axis = Axis(address)
    if (
        length == _VARIABLE_SLEW_LENGTH
        and code in (_POSITIVE_VARIABLE, _NEGATIVE_VARIABLE)
        and data3 == reply_length == 0
    ):
        return VariableRateSlew(axis, code == _POSITIVE_VARIABLE, (data1 << 8) | data2)
    if (
        length == _FIXED_SLEW_LENGTH
        and code in (_POSITIVE_FIXED, _NEGATIVE_FIXED)
        and data1 <= 9
        and data2 == data3 == reply_length == 0
    ):
        return FixedRateSlew(axis, code == _POSITIVE_FIXED, data1)
    if (
        length == _VERSION_QUERY_LENGTH
        and code == _GET_VERSION
        and data1 == data2 == data3 == 0
        and reply_length == _DEVICE_VERSION_REPLY_LENGTH
    ):
        return GetDeviceVersion(axis)
    if length == _POSITION_LENGTH and code in (_SLOW_GOTO, _SET_POSITION) and reply_length == 0:
        position = angles.bytes_to_position24(data1, data2, data3)
        return SlowGoto(axis, position) if code == _SLOW_GOTO else SetAxisPosition(axis, position)
    return None


@dataclass(frozen=True, slots=True)
class GetLocation(Command):
    """``w``: read the site location."""

    def describe(self) -> str:
        return "get location"


@dataclass(frozen=True, slots=True)
class SetLocation(Command):
    """``W`` + 8 bytes: set the site location."""

    location: Location

    def describe(self) -> str:
        return f"set location {self.location.describe()}"


@dataclass(frozen=True, slots=True)
class GetTime(Command):
    """``h``: read the local date, time and time zone."""

    def describe(self) -> str:
        return "get time"


@dataclass(frozen=True, slots=True)
class SetTime(Command):
    """``H`` + 8 bytes: set the local date, time and time zone."""

    time: DateTime

    def describe(self) -> str:
        return f"set time {self.time.describe()}"


@dataclass(frozen=True, slots=True)
class GetVersion(Command):
    """``V``: read the hand control's firmware version."""

    def describe(self) -> str:
        return "get hand control version"


@dataclass(frozen=True, slots=True)
class GetModel(Command):
    """``m``: read the mount model code."""

    def describe(self) -> str:
        return "get mount model"


@dataclass(frozen=True, slots=True)
class Echo(Command):
    """``K`` + byte: the hand control echoes the byte back (handshake and resynchronisation)."""

    value: int

    def __post_init__(self) -> None:
        _check_byte("value", self.value)

    def describe(self) -> str:
        return f"echo {_describe_byte(self.value)}"


def _describe_byte(value: int) -> str:
    printable = chr(value) if 0x20 <= value < 0x7F else None
    return f"0x{value:02X} ({printable!r})" if printable else f"0x{value:02X}"


@dataclass(frozen=True, slots=True)
class IsAligned(Command):
    """``J``: is the alignment complete?"""

    def describe(self) -> str:
        return "is alignment complete?"


@dataclass(frozen=True, slots=True)
class IsGotoInProgress(Command):
    """``L``: is a GOTO in progress?"""

    def describe(self) -> str:
        return "is goto in progress?"


@dataclass(frozen=True, slots=True)
class CancelGoto(Command):
    """``M``: cancel a GOTO."""

    def describe(self) -> str:
        return "cancel goto"


@dataclass(frozen=True, slots=True)
class GetPointingState(Command):
    """``p``: which side of the meridian the tube is on."""

    def describe(self) -> str:
        return "get pointing state"


PassthroughCommand = (
    VariableRateSlew | FixedRateSlew | GetDeviceVersion | SlowGoto | SetAxisPosition | Passthrough
)
"""Every command sent as ``P`` + 7 bytes."""

AnyCommand = (
    GetRaDec
    | GetAzAlt
    | GotoRaDec
    | GotoAzAlt
    | SyncRaDec
    | GetTrackingMode
    | SetTrackingMode
    | PassthroughCommand
    | GetLocation
    | SetLocation
    | GetTime
    | SetTime
    | GetVersion
    | GetModel
    | Echo
    | IsAligned
    | IsGotoInProgress
    | CancelGoto
    | GetPointingState
)
"""The closed union of every SynScan command (for exhaustive ``match``)."""


# ----------------------------------------------------------------------------------------- replies


@dataclass(frozen=True, slots=True)
class Ack(Reply):
    """A bare ``#``: the command was accepted (it says nothing about whether it was obeyed)."""

    def describe(self) -> str:
        return "ok"


@dataclass(frozen=True, slots=True)
class Position(Reply):
    """The reply to ``E e Z z``: two angles in wire units."""

    frame: Frame
    axis1_units: int
    axis2_units: int
    precise: bool = True

    def __post_init__(self) -> None:
        _check_units("axis1_units", self.axis1_units, self.precise)
        _check_units("axis2_units", self.axis2_units, self.precise)

    @classmethod
    def from_ra_dec(cls, ra_hours: float, dec_degrees: float, precise: bool = True) -> Position:
        """A RA/Dec reply from RA in hours and Dec in degrees."""
        return cls(Frame.EQUATORIAL, *_ra_dec_units(ra_hours, dec_degrees, precise), precise)

    @classmethod
    def from_az_alt(cls, az_degrees: float, alt_degrees: float, precise: bool = True) -> Position:
        """An Az/Alt reply from degrees."""
        return cls(
            Frame.HORIZONTAL,
            angles.degrees_to_units(az_degrees, precise),
            angles.degrees_to_units(alt_degrees, precise),
            precise,
        )

    @property
    def axis1_degrees(self) -> float:
        """RA or Az in degrees, [0, 360)."""
        return angles.units_to_degrees(self.axis1_units, self.precise)

    @property
    def axis2_degrees(self) -> float:
        """Dec or Alt in degrees, folded into [-90, 90] (see `flipped`)."""
        return angles.fold_over_pole(self._axis2_signed)[0]

    @property
    def flipped(self) -> bool:
        """Whether Dec/Alt was read back beyond ±90° and had to be folded."""
        return angles.fold_over_pole(self._axis2_signed)[1]

    @property
    def _axis2_signed(self) -> float:
        return angles.units_to_signed_degrees(self.axis2_units, self.precise)

    @property
    def ra_hours(self) -> float:
        """RA in hours (equatorial frame)."""
        return angles.degrees_to_hours(self.axis1_degrees)

    @property
    def dec_degrees(self) -> float:
        """Dec in degrees, folded (equatorial frame)."""
        return self.axis2_degrees

    @property
    def az_degrees(self) -> float:
        """Azimuth in degrees (horizontal frame)."""
        return self.axis1_degrees

    @property
    def alt_degrees(self) -> float:
        """Altitude in degrees, folded (horizontal frame)."""
        return self.axis2_degrees

    def describe(self) -> str:
        if self.frame is Frame.EQUATORIAL:
            return _describe_ra_dec(self.axis1_units, self.axis2_units, self.precise)
        return _describe_az_alt(self.axis1_units, self.axis2_units, self.precise)


@dataclass(frozen=True, slots=True)
class TrackingMode(Reply):
    """The reply to ``t``: the tracking mode byte (see `Tracking`)."""

    mode: int

    def __post_init__(self) -> None:
        _check_byte("mode", self.mode)

    def describe(self) -> str:
        return f"tracking mode {_describe_tracking(self.mode)}"


@dataclass(frozen=True, slots=True)
class Location(Reply):
    """Site location as on the wire (``w`` reply, ``W`` payload): d/m/s, N/S, d/m/s, E/W."""

    lat_degrees: int
    lat_minutes: int
    lat_seconds: int
    south: bool
    lon_degrees: int
    lon_minutes: int
    lon_seconds: int
    west: bool

    def __post_init__(self) -> None:
        for name in ("lat_degrees", "lat_minutes", "lat_seconds"):
            _check_byte(name, getattr(self, name))
        for name in ("lon_degrees", "lon_minutes", "lon_seconds"):
            _check_byte(name, getattr(self, name))

    @classmethod
    def from_degrees(cls, latitude: float, longitude: float) -> Location:
        """From signed degrees (north and east positive), rounded to the arcsecond."""
        if not -90.0 <= latitude <= 90.0:
            raise ValueError(f"latitude must be in -90..90, got {latitude}")
        longitude = (longitude + 180.0) % 360.0 - 180.0
        return cls(*_dms(latitude), latitude < 0, *_dms(longitude), longitude < 0)

    @property
    def latitude(self) -> float:
        """Latitude in degrees, north positive."""
        value = self.lat_degrees + self.lat_minutes / 60 + self.lat_seconds / 3600
        return -value if self.south else value

    @property
    def longitude(self) -> float:
        """Longitude in degrees, east positive."""
        value = self.lon_degrees + self.lon_minutes / 60 + self.lon_seconds / 3600
        return -value if self.west else value

    def describe(self) -> str:
        lat = f"{self.lat_degrees}°{self.lat_minutes:02d}'{self.lat_seconds:02d}\""
        lon = f"{self.lon_degrees}°{self.lon_minutes:02d}'{self.lon_seconds:02d}\""
        return f"{lat}{'S' if self.south else 'N'} {lon}{'W' if self.west else 'E'}"


def _dms(degrees: float) -> tuple[int, int, int]:
    whole_minutes, seconds = divmod(round(abs(degrees) * 3600), 60)
    whole_degrees, minutes = divmod(whole_minutes, 60)
    return whole_degrees, minutes, seconds


YEAR_BASE = 2000
"""The year byte counts from 2000 (the spec: "century assumed as 20")."""


@dataclass(frozen=True, slots=True)
class DateTime(Reply):
    """Local date and time as on the wire (``h`` reply, ``H`` payload).

    ``utc_offset_hours`` is the standard-time zone (the byte is two's complement: -5 <-> 251); when
    ``dst`` is set the local clock is one hour further ahead of UTC.
    """

    hour: int
    minute: int
    second: int
    month: int
    day: int
    year: int
    utc_offset_hours: int
    dst: bool

    def __post_init__(self) -> None:
        for name in ("hour", "minute", "second", "month", "day"):
            _check_byte(name, getattr(self, name))
        _check_range("year", self.year, YEAR_BASE, YEAR_BASE + 0xFF)
        _check_range("utc_offset_hours", self.utc_offset_hours, -128, 127)

    @classmethod
    def from_datetime(cls, local: dt.datetime, dst: bool = False) -> DateTime:
        """From an aware local datetime; its UTC offset includes the DST hour when ``dst`` is
        set."""
        offset = local.utcoffset()
        if offset is None:
            raise ValueError("the datetime must be timezone-aware")
        offset_hours, remainder = divmod(offset, dt.timedelta(hours=1))
        if remainder:
            raise ValueError(f"SynScan time zones are whole hours, got UTC offset {offset}")
        return cls(
            local.hour,
            local.minute,
            local.second,
            local.month,
            local.day,
            local.year,
            offset_hours - int(dst),
            dst,
        )

    def to_datetime(self) -> dt.datetime:
        """The local time as an aware datetime (its offset includes the DST hour)."""
        zone = dt.timezone(dt.timedelta(hours=self.utc_offset_hours + int(self.dst)))
        return dt.datetime(
            self.year, self.month, self.day, self.hour, self.minute, self.second, tzinfo=zone
        )

    def describe(self) -> str:
        date = f"{self.year:04d}-{self.month:02d}-{self.day:02d}"
        clock = f"{self.hour:02d}:{self.minute:02d}:{self.second:02d}"
        zone = f"UTC{self.utc_offset_hours:+d}" if self.utc_offset_hours else "UTC"
        return f"{date} {clock} {zone}{' DST' if self.dst else ''}"


class VersionDialect(Enum):
    """How a ``V`` reply is shaped."""

    SYNSCAN_HEX = "SynScan: 6 uppercase hex digits + #"
    NEXSTAR_BINARY = "Celestron NexStar: 2 binary bytes + #"
    SYNSCAN_BINARY = "old SynScan: 3 binary bytes + #"


@dataclass(frozen=True, slots=True)
class Version(Reply):
    """The reply to ``V``: hand control firmware version (``042507#`` is 4.37.07).

    ``patch`` is None in the NexStar dialect, which has only two numbers. Binary dialects cannot
    start with an ASCII hex digit and the old SynScan one cannot have patch 35 (``#``): such replies
    would be read as another dialect (see the protocol notes)."""

    major: int
    minor: int
    patch: int | None
    dialect: VersionDialect = VersionDialect.SYNSCAN_HEX

    def __post_init__(self) -> None:
        _check_byte("major", self.major)
        _check_byte("minor", self.minor)
        if (self.patch is None) != (self.dialect is VersionDialect.NEXSTAR_BINARY):
            raise ValueError("patch is None exactly in the NexStar dialect")
        if self.patch is not None:
            _check_byte("patch", self.patch)
        if self.dialect is not VersionDialect.SYNSCAN_HEX and angles.is_hex_digit(self.major):
            raise ValueError(
                f"a binary version cannot start with byte {self.major:#04x} (hex digit)"
            )
        if self.dialect is VersionDialect.SYNSCAN_BINARY and self.patch == HASH:
            raise ValueError("an old SynScan binary version cannot have patch 35 ('#')")

    def as_tuple(self) -> tuple[int, int, int]:
        """(major, minor, patch) for comparisons; patch 0 in the NexStar dialect."""
        return self.major, self.minor, self.patch or 0

    def describe(self) -> str:
        if self.patch is None:
            return f"version {self.major}.{self.minor} (Celestron NexStar)"
        suffix = "" if self.dialect is VersionDialect.SYNSCAN_HEX else " (old binary form)"
        return f"version {self.major}.{self.minor:02d}.{self.patch:02d}{suffix}"


_MODEL_NAMES = {
    0: "EQ6 GOTO",
    1: "HEQ5 GOTO",
    2: "EQ5 GOTO",
    3: "EQ3 GOTO",
    4: "EQ8 GOTO",
    5: "AZ-EQ6 GOTO",
    6: "AZ-EQ5 GOTO",
    160: "AllView GOTO",
    161: "Virtuoso",
    165: "AZ-GTi",
}
_AZ_GOTO_CODES = range(128, 144)
_DOB_GOTO_CODES = range(144, 160)


@dataclass(frozen=True, slots=True)
class Model(Reply):
    """The reply to ``m``: the mount model code.

    ``swapped`` marks the dialect of some firmware (3.39) that sends ``#`` before the code.
    """

    code: int
    swapped: bool = False

    def __post_init__(self) -> None:
        _check_byte("code", self.code)
        if self.swapped and self.code == HASH:
            raise ValueError(
                "a swapped model reply cannot carry code 35 ('#'): it reads as unswapped"
            )

    @property
    def name(self) -> str:
        """The model series, or "unknown model"."""
        if self.code in _AZ_GOTO_CODES:
            return "AZ GOTO"
        if self.code in _DOB_GOTO_CODES:
            return "Dob GOTO"
        return _MODEL_NAMES.get(self.code, "unknown model")

    @property
    def is_equatorial(self) -> bool:
        """Whether the code is an equatorial (or dual-mode AZ-EQ) mount: codes below 128."""
        return self.code < 128

    def describe(self) -> str:
        swapped = ", '#' first" if self.swapped else ""
        return f"model {self.code} ({self.name}{swapped})"


@dataclass(frozen=True, slots=True)
class EchoReply(Reply):
    """The reply to ``K``: the echoed byte."""

    value: int

    def __post_init__(self) -> None:
        _check_byte("value", self.value)

    def describe(self) -> str:
        return f"echo {_describe_byte(self.value)}"


@dataclass(frozen=True, slots=True)
class Aligned(Reply):
    """The reply to ``J``: binary 0x00/0x01."""

    aligned: bool

    def describe(self) -> str:
        return "aligned" if self.aligned else "not aligned"


@dataclass(frozen=True, slots=True)
class GotoInProgress(Reply):
    """The reply to ``L``: ASCII '0'/'1'."""

    in_progress: bool

    def describe(self) -> str:
        return "goto in progress" if self.in_progress else "no goto in progress"


class PointingSide(StrEnum):
    """The ``p`` reply: 'E' is not flipped in the northern hemisphere, 'W' flipped (reversed
    south)."""

    EAST = "E"
    WEST = "W"


@dataclass(frozen=True, slots=True)
class PointingState(Reply):
    """The reply to ``p``: ASCII 'E' or 'W'."""

    side: PointingSide

    def describe(self) -> str:
        return f"pointing state {self.side.value} (tube on the {self.side.name.lower()} side)"


@dataclass(frozen=True, slots=True)
class DeviceVersion(Reply):
    """The reply to `GetDeviceVersion`: motor controller firmware major, minor."""

    major: int
    minor: int

    def __post_init__(self) -> None:
        _check_byte("major", self.major)
        _check_byte("minor", self.minor)

    def describe(self) -> str:
        return f"motor controller version {self.major}.{self.minor}"


@dataclass(frozen=True, slots=True)
class PassthroughReply(Reply):
    """The reply to a raw `Passthrough`: the requested bytes (the ``#`` not included)."""

    data: bytes

    def describe(self) -> str:
        return f"passthrough reply {self.data.hex(' ').upper()}" if self.data else "ok"


@dataclass(frozen=True, slots=True)
class PassthroughFailed(Reply):
    """A failed passthrough: the requested bytes, then one extra byte, then ``#``.

    An extra byte equal to ``#`` cannot be told from success, so it is refused.
    """

    data: bytes
    extra: int

    def __post_init__(self) -> None:
        _check_byte("extra", self.extra)
        if self.extra == HASH:
            raise ValueError("the extra byte of a failed passthrough cannot be '#'")

    def describe(self) -> str:
        data = f" after {self.data.hex(' ').upper()}" if self.data else ""
        return f"passthrough failed (extra byte 0x{self.extra:02X}{data})"


AnyReply = (
    Ack
    | Position
    | TrackingMode
    | Location
    | DateTime
    | Version
    | Model
    | EchoReply
    | Aligned
    | GotoInProgress
    | PointingState
    | DeviceVersion
    | PassthroughReply
    | PassthroughFailed
)
"""The closed union of every SynScan reply."""
