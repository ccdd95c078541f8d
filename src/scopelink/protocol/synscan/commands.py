"""SynScan commands (PC -> hand control), one class each, except the passthrough (``P``) family
(`scopelink.protocol.synscan.passthrough`).

A class carries its letters and frame lengths (`frames`), its encoding and decoding, and the shape
of its reply and how it is read. A command is framed by the length its first letter implies, never
by a terminator: binary payloads (``W``, ``H``, ``K``, ``T``) may hold any byte."""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar, Self

from scopelink.protocol.synscan import angles
from scopelink.protocol.synscan.message import (
    Command,
    FieldError,
    ReplyShape,
    ScanResult,
    letter_frames,
)
from scopelink.protocol.synscan.replies import (
    Ack,
    Aligned,
    DateTime,
    EchoReply,
    GotoInProgress,
    Location,
    Model,
    PointingState,
    Position,
    TrackingModeReply,
    Version,
)
from scopelink.protocol.synscan.scanning import (
    allowed_bytes,
    decode_hex_pair,
    encode_hex_pair,
    flag_check,
    scan_terminated,
)
from scopelink.protocol.synscan.values import (
    Frame,
    PointingSide,
    check_byte,
    check_units,
    describe_az_alt,
    describe_byte,
    describe_ra_dec,
    describe_tracking,
    precision_word,
    ra_dec_units,
)

_ACK_SHAPE = ReplyShape((1,), "'#'")


class _Acknowledged(Command):
    """A command answered by a bare ``#`` that moves the mount or changes a setting."""

    __slots__ = ()
    changes_mount = True

    def reply_shape(self) -> ReplyShape:
        return _ACK_SHAPE

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        return scan_terminated(buffer, 0, None, lambda body: Ack())


class _Letter(Command):
    """A command that is its letter alone (`letter`)."""

    __slots__ = ()
    letter: ClassVar[bytes]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "letter" in cls.__dict__:
            cls.frames = letter_frames(cls.letter, 1)

    @classmethod
    def decode(cls, frame: bytes) -> Self:
        return cls()

    def encode(self) -> bytes:
        return self.letter


class _Precise(Command):
    """A command with a standard letter (16-bit angles) and a precise one (32-bit angles)."""

    __slots__ = ()
    letters: ClassVar[bytes]
    """The standard letter, then the precise one."""

    precise: bool

    def sent_letter(self) -> bytes:
        """The letter this command is sent with."""
        return self.letters[1:] if self.precise else self.letters[:1]

    @classmethod
    def is_precise(cls, frame: bytes) -> bool:
        """Whether ``frame`` starts with the precise letter."""
        return frame[0] == cls.letters[1]


# --------------------------------------------------------------------------------- positions


@dataclass(frozen=True, slots=True)
class _PositionQuery(_Precise):
    """Shared shape of the position reads: the reply is two hex angles, ``,`` between."""

    precise: bool = True
    repeats_reply = True

    coordinates: ClassVar[Frame]
    """Which pair of coordinates the reply carries."""

    @classmethod
    def decode(cls, frame: bytes) -> Self:
        return cls(precise=cls.is_precise(frame))

    def encode(self) -> bytes:
        # sent_letter() inline: every poll encodes one (issue #14: CPU per command)
        return self.letters[1:] if self.precise else self.letters[:1]

    def reply_shape(self) -> ReplyShape:
        width = angles.hex_width(self.precise)
        return ReplyShape((2 * width + 2,), f"{width} hex, ',', {width} hex, '#'")

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        return Position.scan(buffer, self.coordinates, self.precise)


class GetRaDec(_PositionQuery):
    """``E`` (or ``e`` when precise): read RA/Dec (J2000)."""

    __slots__ = ()
    letters = b"Ee"
    frames = letter_frames(letters, 1)
    coordinates = Frame.EQUATORIAL

    def describe(self) -> str:
        return f"get {precision_word(self.precise)}RA/Dec"


class GetAzAlt(_PositionQuery):
    """``Z`` (or ``z`` when precise): read Az/Alt."""

    __slots__ = ()
    letters = b"Zz"
    frames = letter_frames(letters, 1)
    coordinates = Frame.HORIZONTAL

    def describe(self) -> str:
        return f"get {precision_word(self.precise)}Az/Alt"


def _pair_frames(letters: bytes) -> dict[int, int]:
    """Frames of a command carrying two angles: letter, hex, ``,``, hex."""
    return {
        letters[0]: 2 + 2 * angles.hex_width(False),
        letters[1]: 2 + 2 * angles.hex_width(True),
    }


def _decode_pair(cls: type[_Precise], frame: bytes) -> tuple[int, int, bool] | FieldError:
    precise = cls.is_precise(frame)
    pair = decode_hex_pair(frame[1:], precise)
    return pair.shifted(1) if isinstance(pair, FieldError) else (*pair, precise)


@dataclass(frozen=True, slots=True)
class _RaDecTarget(_Precise, _Acknowledged):
    """Shared shape of goto and sync on RA/Dec (J2000). Units as on the wire."""

    ra_units: int
    dec_units: int
    precise: bool = True

    _VERB: ClassVar[str] = ""

    def __post_init__(self) -> None:
        check_units("ra_units", self.ra_units, self.precise)
        check_units("dec_units", self.dec_units, self.precise)

    @classmethod
    def from_hours_degrees(cls, ra_hours: float, dec_degrees: float, precise: bool = True) -> Self:
        """From RA in hours and Dec in degrees (negative Dec becomes the two's complement)."""
        return cls(*ra_dec_units(ra_hours, dec_degrees, precise), precise)

    @classmethod
    def decode(cls, frame: bytes) -> Self | FieldError:
        pair = _decode_pair(cls, frame)
        return pair if isinstance(pair, FieldError) else cls(*pair)

    def encode(self) -> bytes:
        return self.sent_letter() + encode_hex_pair(self.ra_units, self.dec_units, self.precise)

    @property
    def ra_hours(self) -> float:
        """Right ascension in hours, [0, 24)."""
        return angles.degrees_to_hours(angles.units_to_degrees(self.ra_units, self.precise))

    @property
    def dec_degrees(self) -> float:
        """Declination in degrees, two's complement read: [-180, 180)."""
        return angles.units_to_signed_degrees(self.dec_units, self.precise)

    def describe(self) -> str:
        detail = describe_ra_dec(self.ra_units, self.dec_units, self.precise)
        return f"{precision_word(self.precise)}{self._VERB} {detail}"


class GotoRaDec(_RaDecTarget):
    """``R`` (or ``r`` when precise): goto RA/Dec (J2000)."""

    __slots__ = ()
    letters = b"Rr"
    frames = _pair_frames(letters)
    _VERB = "goto"


class SyncRaDec(_RaDecTarget):
    """``S`` (or ``s`` when precise): sync on RA/Dec (J2000)."""

    __slots__ = ()
    letters = b"Ss"
    frames = _pair_frames(letters)
    _VERB = "sync"


@dataclass(frozen=True, slots=True)
class GotoAzAlt(_Precise, _Acknowledged):
    """``B`` (or ``b`` when precise): goto Az/Alt. Units as on the wire."""

    az_units: int
    alt_units: int
    precise: bool = True

    letters = b"Bb"
    frames = _pair_frames(letters)

    def __post_init__(self) -> None:
        check_units("az_units", self.az_units, self.precise)
        check_units("alt_units", self.alt_units, self.precise)

    @classmethod
    def from_degrees(cls, az_degrees: float, alt_degrees: float, precise: bool = True) -> Self:
        """Goto azimuth and altitude in degrees."""
        return cls(
            angles.degrees_to_units(az_degrees, precise),
            angles.degrees_to_units(alt_degrees, precise),
            precise,
        )

    @classmethod
    def decode(cls, frame: bytes) -> Self | FieldError:
        pair = _decode_pair(cls, frame)
        return pair if isinstance(pair, FieldError) else cls(*pair)

    def encode(self) -> bytes:
        return self.sent_letter() + encode_hex_pair(self.az_units, self.alt_units, self.precise)

    @property
    def az_degrees(self) -> float:
        """Azimuth in degrees, [0, 360)."""
        return angles.units_to_degrees(self.az_units, self.precise)

    @property
    def alt_degrees(self) -> float:
        """Altitude in degrees, two's complement read: [-180, 180)."""
        return angles.units_to_signed_degrees(self.alt_units, self.precise)

    def describe(self) -> str:
        detail = describe_az_alt(self.az_units, self.alt_units, self.precise)
        return f"{precision_word(self.precise)}goto {detail}"


# ---------------------------------------------------------------------------------- tracking


@dataclass(frozen=True, slots=True)
class GetTrackingMode(_Letter):
    """``t``: read the tracking mode."""

    letter = b"t"
    repeats_reply = True

    def reply_shape(self) -> ReplyShape:
        return ReplyShape((2,), "binary mode byte, '#'")

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        return scan_terminated(buffer, 1, None, lambda body: TrackingModeReply(body[0]))

    def describe(self) -> str:
        return "get tracking mode"


@dataclass(frozen=True, slots=True)
class SetTrackingMode(_Acknowledged):
    """``T`` + mode byte: set the tracking mode (see `Tracking`)."""

    mode: int

    frames = letter_frames(b"T", 2)

    def __post_init__(self) -> None:
        check_byte("mode", self.mode)

    @classmethod
    def decode(cls, frame: bytes) -> Self:
        return cls(frame[1])

    def encode(self) -> bytes:
        return bytes((ord("T"), self.mode))

    def describe(self) -> str:
        return f"set tracking mode {describe_tracking(self.mode)}"


# ------------------------------------------------------------------------ location and time

_EIGHT_BYTES = ReplyShape((9,), "8 binary bytes, '#'")


class _ReadEightBytes(_Letter):
    """Reads a value of 8 binary bytes (`Location`, `DateTime`); its flag bytes are 0 or 1."""

    __slots__ = ()
    _VALUE: ClassVar[type[Location] | type[DateTime]]
    _FLAGS: ClassVar[tuple[int, ...]]

    def reply_shape(self) -> ReplyShape:
        return _EIGHT_BYTES

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        return scan_terminated(buffer, 8, flag_check(*self._FLAGS), self._VALUE.from_body)


class _SetEightBytes(_Acknowledged):
    """Sets a value of 8 binary bytes: its letter, then the bytes of its reply form."""

    __slots__ = ()
    _LETTER: ClassVar[bytes]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "_LETTER" in cls.__dict__:
            cls.frames = letter_frames(cls._LETTER, 9)

    @abstractmethod
    def _value(self) -> Location | DateTime:
        """The value set."""

    def encode(self) -> bytes:
        return self._LETTER + self._value().body()


@dataclass(frozen=True, slots=True)
class GetLocation(_ReadEightBytes):
    """``w``: read the site location."""

    letter = b"w"
    _VALUE = Location
    _FLAGS = (3, 7)

    def describe(self) -> str:
        return "get location"


@dataclass(frozen=True, slots=True)
class SetLocation(_SetEightBytes):
    """``W`` + 8 bytes: set the site location."""

    location: Location

    _LETTER = b"W"

    @classmethod
    def decode(cls, frame: bytes) -> Self | FieldError:
        location = Location.from_body(frame[1:])
        return location.shifted(1) if isinstance(location, FieldError) else cls(location)

    def _value(self) -> Location:
        return self.location

    def describe(self) -> str:
        return f"set location {self.location.describe()}"


@dataclass(frozen=True, slots=True)
class GetTime(_ReadEightBytes):
    """``h``: read the local date, time and time zone."""

    letter = b"h"
    _VALUE = DateTime
    _FLAGS = (7,)

    def describe(self) -> str:
        return "get time"


@dataclass(frozen=True, slots=True)
class SetTime(_SetEightBytes):
    """``H`` + 8 bytes: set the local date, time and time zone."""

    time: DateTime

    _LETTER = b"H"

    @classmethod
    def decode(cls, frame: bytes) -> Self | FieldError:
        time = DateTime.from_body(frame[1:])
        return time.shifted(1) if isinstance(time, FieldError) else cls(time)

    def _value(self) -> DateTime:
        return self.time

    def describe(self) -> str:
        return f"set time {self.time.describe()}"


# ------------------------------------------------------------------------ the hand control


@dataclass(frozen=True, slots=True)
class GetVersion(_Letter):
    """``V``: read the hand control's firmware version."""

    letter = b"V"

    def reply_shape(self) -> ReplyShape:
        return ReplyShape(
            (7, 3, 4), "6 hex digits + '#', or 2 (NexStar) or 3 (old SynScan) binary bytes + '#'"
        )

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        return Version.scan(buffer)

    def describe(self) -> str:
        return "get hand control version"


@dataclass(frozen=True, slots=True)
class GetModel(_Letter):
    """``m``: read the mount model code."""

    letter = b"m"

    def reply_shape(self) -> ReplyShape:
        return ReplyShape((2,), "binary model byte, '#' (or '#' first on some firmware)")

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        return Model.scan(buffer)

    def describe(self) -> str:
        return "get mount model"


@dataclass(frozen=True, slots=True)
class Echo(Command):
    """``K`` + byte: the hand control echoes the byte back (handshake and resynchronisation)."""

    value: int

    frames = letter_frames(b"K", 2)

    def __post_init__(self) -> None:
        check_byte("value", self.value)

    @classmethod
    def decode(cls, frame: bytes) -> Self:
        return cls(frame[1])

    def encode(self) -> bytes:
        return bytes((ord("K"), self.value))

    def reply_shape(self) -> ReplyShape:
        return ReplyShape((2,), "the echoed byte, '#'")

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        check = allowed_bytes(bytes((self.value,)))
        return scan_terminated(buffer, 1, check, lambda body: EchoReply(body[0]))

    def describe(self) -> str:
        return f"echo {describe_byte(self.value)}"


@dataclass(frozen=True, slots=True)
class IsAligned(_Letter):
    """``J``: is the alignment complete?"""

    letter = b"J"
    repeats_reply = True

    def reply_shape(self) -> ReplyShape:
        return ReplyShape((2,), "binary 0x00/0x01, '#'")

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        check = allowed_bytes(b"\x00\x01")
        return scan_terminated(buffer, 1, check, lambda body: Aligned(body[0] == 1))

    def describe(self) -> str:
        return "is alignment complete?"


@dataclass(frozen=True, slots=True)
class IsGotoInProgress(_Letter):
    """``L``: is a GOTO in progress?"""

    letter = b"L"
    repeats_reply = True

    def reply_shape(self) -> ReplyShape:
        return ReplyShape((2,), "ASCII '0'/'1', '#'")

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        check = allowed_bytes(b"01")
        return scan_terminated(buffer, 1, check, lambda body: GotoInProgress(body == b"1"))

    def describe(self) -> str:
        return "is goto in progress?"


@dataclass(frozen=True, slots=True)
class CancelGoto(_Letter, _Acknowledged):
    """``M``: cancel a GOTO."""

    letter = b"M"

    def describe(self) -> str:
        return "cancel goto"


@dataclass(frozen=True, slots=True)
class GetPointingState(_Letter):
    """``p``: which side of the meridian the tube is on."""

    letter = b"p"
    repeats_reply = True

    def reply_shape(self) -> ReplyShape:
        return ReplyShape((2,), "ASCII 'E'/'W', '#'")

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        return scan_terminated(
            buffer,
            1,
            allowed_bytes(b"EW"),
            lambda body: PointingState(PointingSide(body.decode())),
        )

    def describe(self) -> str:
        return "get pointing state"
