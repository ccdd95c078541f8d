"""SynScan replies (hand control -> PC), each with its bytes and, where the reply reads the same
whatever asked for it, its reader.

Every reply stores the wire's integer units exactly, so encoding and parsing round-trip bit for
bit, and offers plain units as properties and ``from_...`` constructors."""

from __future__ import annotations

import datetime as dt
import re
from dataclasses import dataclass
from typing import Final, Self

from scopelink.protocol.base import NEED_DATA
from scopelink.protocol.synscan import angles
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.message import (
    TERMINATOR,
    Complete,
    FieldError,
    Mismatch,
    Reply,
    ScanResult,
)
from scopelink.protocol.synscan.scanning import (
    decode_hex_pair,
    encode_hex_pair,
    hex_check,
    scan_terminated,
)
from scopelink.protocol.synscan.values import (
    Frame,
    PointingSide,
    VersionDialect,
    check_byte,
    check_range,
    check_units,
    describe_az_alt,
    describe_byte,
    describe_ra_dec,
    describe_tracking,
    ra_dec_units,
)

_VERSION_HEX_DIGITS = 6

_set_field = object.__setattr__
"""Sets a field of a frozen dataclass (as its generated ``__init__`` does)."""
_NEXSTAR_VERSION_BYTES = 2
_BINARY_SYNSCAN_VERSION_BYTES = 3


@dataclass(frozen=True, slots=True)
class Ack(Reply):
    """A bare ``#``: the command was accepted (it says nothing about whether it was obeyed)."""

    def describe(self) -> str:
        return "ok"

    def body(self) -> bytes:
        return b""


_WHOLE_POSITION: Final = {
    precise: re.compile(rb"([0-9A-Fa-f]{%d}),([0-9A-Fa-f]{%d})#" % (width, width))
    for precise, width in ((True, angles.hex_width(True)), (False, angles.hex_width(False)))
}
"""A complete, well-formed position reply at the start of a buffer (what nearly every poll gets);
anything else is scanned byte by byte, for the exact mismatch or how much is still missing."""


@dataclass(frozen=True, slots=True)
class Position(Reply):
    """The reply to ``E e Z z``: two angles in wire units."""

    frame: Frame
    axis1_units: int
    axis2_units: int
    precise: bool = True

    def __post_init__(self) -> None:
        check_units("axis1_units", self.axis1_units, self.precise)
        check_units("axis2_units", self.axis2_units, self.precise)

    @classmethod
    def from_ra_dec(cls, ra_hours: float, dec_degrees: float, precise: bool = True) -> Position:
        """A RA/Dec reply from RA in hours and Dec in degrees."""
        return cls(Frame.EQUATORIAL, *ra_dec_units(ra_hours, dec_degrees, precise), precise)

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
            return describe_ra_dec(self.axis1_units, self.axis2_units, self.precise)
        return describe_az_alt(self.axis1_units, self.axis2_units, self.precise)

    def body(self) -> bytes:
        return encode_hex_pair(self.axis1_units, self.axis2_units, self.precise)

    @classmethod
    def _in_range(cls, frame: Frame, axis1_units: int, axis2_units: int, precise: bool) -> Self:
        """A position from units already known to be in range (each parsed from exactly
        ``hex_width(precise)`` hex digits, so below ``units_per_revolution(precise)``): the
        checks of ``__post_init__`` are skipped. Every reply is parsed here (issue #14: CPU per
        command); the bytes and the values are those of the checked constructor."""
        position = object.__new__(cls)
        _set_field(position, "frame", frame)
        _set_field(position, "axis1_units", axis1_units)
        _set_field(position, "axis2_units", axis2_units)
        _set_field(position, "precise", precise)
        return position

    @classmethod
    def scan(cls, buffer: bytes | bytearray, frame: Frame, precise: bool) -> ScanResult:
        """Read a position of ``frame`` and precision at the start of ``buffer``."""
        whole = _WHOLE_POSITION[precise].match(buffer)
        if whole is not None:
            first, second = whole.groups()
            return Complete(
                cls._in_range(frame, int(first, 16), int(second, 16), precise), whole.end()
            )
        width = angles.hex_width(precise)

        def check(index: int, value: int) -> str | None:
            if index == width:
                return None if value == ord(",") else f"expected ',', got 0x{value:02X}"
            return hex_check(index, value)

        def build(body: bytes) -> Position | FieldError:
            pair = decode_hex_pair(body, precise)
            return pair if isinstance(pair, FieldError) else cls(frame, *pair, precise)

        return scan_terminated(buffer, 2 * width + 1, check, build)


@dataclass(frozen=True, slots=True)
class TrackingModeReply(Reply):
    """The reply to ``t``: the tracking mode byte (see `Tracking`)."""

    mode: int

    def __post_init__(self) -> None:
        check_byte("mode", self.mode)

    def describe(self) -> str:
        return f"tracking mode {describe_tracking(self.mode)}"

    def body(self) -> bytes:
        return bytes((self.mode,))


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
            check_byte(name, getattr(self, name))
        for name in ("lon_degrees", "lon_minutes", "lon_seconds"):
            check_byte(name, getattr(self, name))

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

    def body(self) -> bytes:
        """The 8 bytes of a location (``W`` payload, ``w`` reply without ``#``)."""
        return bytes(
            (
                self.lat_degrees,
                self.lat_minutes,
                self.lat_seconds,
                int(self.south),
                self.lon_degrees,
                self.lon_minutes,
                self.lon_seconds,
                int(self.west),
            )
        )

    @classmethod
    def from_body(cls, payload: bytes) -> Location | FieldError:
        """A location from its 8 bytes; the hemisphere flags must be 0 or 1."""
        for index in (3, 7):
            if payload[index] > 1:
                return FieldError(index, f"hemisphere flag must be 0 or 1, got {payload[index]}")
        lat_d, lat_m, lat_s, south, lon_d, lon_m, lon_s, west = payload
        return cls(lat_d, lat_m, lat_s, bool(south), lon_d, lon_m, lon_s, bool(west))


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
            check_byte(name, getattr(self, name))
        check_range("year", self.year, YEAR_BASE, YEAR_BASE + 0xFF)
        check_range("utc_offset_hours", self.utc_offset_hours, -128, 127)

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

    def body(self) -> bytes:
        """The 8 bytes of a date and time (``H`` payload, ``h`` reply without ``#``)."""
        return bytes(
            (
                self.hour,
                self.minute,
                self.second,
                self.month,
                self.day,
                self.year - YEAR_BASE,
                self.utc_offset_hours & 0xFF,
                int(self.dst),
            )
        )

    @classmethod
    def from_body(cls, payload: bytes) -> DateTime | FieldError:
        """A date and time from its 8 bytes; the DST flag must be 0 or 1."""
        hour, minute, second, month, day, year, zone, dst = payload
        if dst > 1:
            return FieldError(7, f"DST flag must be 0 or 1, got {dst}")
        offset = zone - 0x100 if zone >= 0x80 else zone
        return cls(hour, minute, second, month, day, YEAR_BASE + year, offset, bool(dst))


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
        check_byte("major", self.major)
        check_byte("minor", self.minor)
        if (self.patch is None) != (self.dialect is VersionDialect.NEXSTAR_BINARY):
            raise ValueError("patch is None exactly in the NexStar dialect")
        if self.patch is not None:
            check_byte("patch", self.patch)
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

    def body(self) -> bytes:
        if self.dialect is VersionDialect.SYNSCAN_HEX:
            return b"%02X%02X%02X" % (self.major, self.minor, self.patch or 0)
        if self.dialect is VersionDialect.NEXSTAR_BINARY:
            return bytes((self.major, self.minor))
        return bytes((self.major, self.minor, self.patch or 0))

    @classmethod
    def scan(cls, buffer: bytes | bytearray) -> ScanResult:
        """Tell the dialect by the first byte: a hex digit means SynScan's 6 hex digits + '#'.

        Otherwise the reply is binary: '#' as third byte ends a 2-byte NexStar version, any other
        third byte is the patch of an old 3-byte SynScan version, which must then be followed by
        '#'."""
        if not buffer:
            return NEED_DATA
        if angles.is_hex_digit(buffer[0]):

            def hex_build(body: bytes) -> Version:
                major, minor, patch = (int(body[i : i + 2], 16) for i in (0, 2, 4))
                return cls(major, minor, patch, VersionDialect.SYNSCAN_HEX)

            return scan_terminated(buffer, _VERSION_HEX_DIGITS, hex_check, hex_build)
        if len(buffer) < _NEXSTAR_VERSION_BYTES + 1:
            return NEED_DATA
        if buffer[_NEXSTAR_VERSION_BYTES] == HASH:
            return Complete(
                cls(buffer[0], buffer[1], None, VersionDialect.NEXSTAR_BINARY),
                _NEXSTAR_VERSION_BYTES + 1,
            )
        return scan_terminated(
            buffer,
            _BINARY_SYNSCAN_VERSION_BYTES,
            None,
            lambda body: cls(body[0], body[1], body[2], VersionDialect.SYNSCAN_BINARY),
        )


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
        check_byte("code", self.code)
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

    def body(self) -> bytes:
        return bytes((self.code,))

    def encode(self) -> bytes:
        return TERMINATOR + self.body() if self.swapped else self.body() + TERMINATOR

    @classmethod
    def scan(cls, buffer: bytes | bytearray) -> ScanResult:
        """``code #``, or ``# code`` from firmware that swaps them (a code of 35 reads as
        unswapped)."""
        if len(buffer) < 2:
            return NEED_DATA
        first, second = buffer[0], buffer[1]
        if second == HASH:
            return Complete(cls(first), 2)
        if first == HASH:
            return Complete(cls(second, swapped=True), 2)
        return Mismatch(1, f"expected '#' before or after the model byte, got 0x{second:02X}")


@dataclass(frozen=True, slots=True)
class EchoReply(Reply):
    """The reply to ``K``: the echoed byte."""

    value: int

    def __post_init__(self) -> None:
        check_byte("value", self.value)

    def describe(self) -> str:
        return f"echo {describe_byte(self.value)}"

    def body(self) -> bytes:
        return bytes((self.value,))


@dataclass(frozen=True, slots=True)
class Aligned(Reply):
    """The reply to ``J``: binary 0x00/0x01."""

    aligned: bool

    def describe(self) -> str:
        return "aligned" if self.aligned else "not aligned"

    def body(self) -> bytes:
        return bytes((int(self.aligned),))


@dataclass(frozen=True, slots=True)
class GotoInProgress(Reply):
    """The reply to ``L``: ASCII '0'/'1'."""

    in_progress: bool

    def describe(self) -> str:
        return "goto in progress" if self.in_progress else "no goto in progress"

    def body(self) -> bytes:
        return b"1" if self.in_progress else b"0"


@dataclass(frozen=True, slots=True)
class PointingState(Reply):
    """The reply to ``p``: ASCII 'E' or 'W'."""

    side: PointingSide

    def describe(self) -> str:
        return f"pointing state {self.side.value} (tube on the {self.side.name.lower()} side)"

    def body(self) -> bytes:
        return self.side.value.encode()


@dataclass(frozen=True, slots=True)
class DeviceVersion(Reply):
    """The reply to `GetDeviceVersion`: motor controller firmware major, minor."""

    major: int
    minor: int

    def __post_init__(self) -> None:
        check_byte("major", self.major)
        check_byte("minor", self.minor)

    def describe(self) -> str:
        return f"motor controller version {self.major}.{self.minor}"

    def body(self) -> bytes:
        return bytes((self.major, self.minor))


@dataclass(frozen=True, slots=True)
class PassthroughReply(Reply):
    """The reply to a raw `Passthrough`: the requested bytes (the ``#`` not included)."""

    data: bytes

    def describe(self) -> str:
        return f"passthrough reply {self.data.hex(' ').upper()}" if self.data else "ok"

    def body(self) -> bytes:
        return self.data


@dataclass(frozen=True, slots=True)
class PassthroughFailed(Reply):
    """A failed passthrough: the requested bytes, then one extra byte, then ``#``.

    An extra byte equal to ``#`` cannot be told from success, so it is refused.
    """

    data: bytes
    extra: int

    def __post_init__(self) -> None:
        check_byte("extra", self.extra)
        if self.extra == HASH:
            raise ValueError("the extra byte of a failed passthrough cannot be '#'")

    def describe(self) -> str:
        data = f" after {self.data.hex(' ').upper()}" if self.data else ""
        return f"passthrough failed (extra byte 0x{self.extra:02X}{data})"

    def body(self) -> bytes:
        return self.data + bytes((self.extra,))
