"""The passthrough (``P`` + 7 bytes) commands: messages the hand control relays to a motor
controller.

Every ``P`` frame is 8 bytes; its payload's last byte is the number of reply bytes before ``#``. A
failed passthrough answers those bytes, one extra byte, then ``#``. Payloads of a known shape are
typed (`TYPED_PASSTHROUGH`); any other is a raw `Passthrough`."""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import ClassVar, Final, Self

from scopelink.protocol.base import NEED_DATA
from scopelink.protocol.synscan import angles
from scopelink.protocol.synscan.angles import HASH
from scopelink.protocol.synscan.message import (
    Command,
    Complete,
    Mismatch,
    Reply,
    ReplyShape,
    ScanResult,
    letter_frames,
)
from scopelink.protocol.synscan.replies import (
    Ack,
    DeviceVersion,
    PassthroughFailed,
    PassthroughReply,
)
from scopelink.protocol.synscan.values import Axis, check_range

PASSTHROUGH_PAYLOAD_LENGTH: Final = 7
"""Bytes after the ``P``."""

_POSITIVE_VARIABLE, _NEGATIVE_VARIABLE = 6, 7
_POSITIVE_FIXED, _NEGATIVE_FIXED = 36, 37
_GET_VERSION = 254
_SLOW_GOTO, _SET_POSITION = 23, 4
_MAX_FIXED_RATE = 9


class PassthroughCommand(Command):
    """Every command sent as ``P`` + 7 bytes."""

    __slots__ = ()
    frames = letter_frames(b"P", 1 + PASSTHROUGH_PAYLOAD_LENGTH)

    @abstractmethod
    def encode_payload(self) -> bytes:
        """The 7 bytes after ``P``."""

    @classmethod
    @abstractmethod
    def from_payload(cls, payload: bytes) -> Self | None:
        """This command from a 7-byte payload, or None when the payload is not its shape."""

    @classmethod
    def decode(cls, frame: bytes) -> Self | None:
        return cls.from_payload(frame[1:])

    def encode(self) -> bytes:
        return b"P" + self.encode_payload()

    @property
    def reply_length(self) -> int:
        """Number of reply bytes before ``#`` (the payload's last byte)."""
        return self.encode_payload()[-1]

    def reply_shape(self) -> ReplyShape:
        count = self.reply_length
        return ReplyShape(
            (count + 1, count + 2), f"{count} bytes, '#' (one extra byte before '#' on failure)"
        )

    def scan_reply(self, buffer: bytes | bytearray) -> ScanResult:
        """``count`` bytes then ``#``; on failure one extra byte comes before the ``#``."""
        count = self.reply_length
        if len(buffer) <= count:
            return NEED_DATA
        data = bytes(buffer[:count])
        if buffer[count] == HASH:
            return Complete(self.success_reply(data), count + 1)
        if len(buffer) <= count + 1:
            return NEED_DATA
        if buffer[count + 1] != HASH:
            return Mismatch(
                count + 1, f"expected '#' after the failure byte, got 0x{buffer[count + 1]:02X}"
            )
        return Complete(PassthroughFailed(data, buffer[count]), count + 2)

    def success_reply(self, data: bytes) -> Reply:
        """The reply when the motor controller answered ``data``."""
        return Ack()


class _AxisCommand(PassthroughCommand):
    """A typed passthrough to one motor controller: ``P length axis code d1 d2 d3 reply_length``.

    A subclass names its ``length``, the codes it may carry and its reply length; it reads and
    writes only its code and three data bytes."""

    __slots__ = ()
    axis: Axis

    _LENGTH: ClassVar[int]
    _CODES: ClassVar[tuple[int, ...]]
    _REPLY_LENGTH: ClassVar[int] = 0

    @classmethod
    def from_payload(cls, payload: bytes) -> Self | None:
        length, address, code, *data, reply_length = payload
        if (
            address not in (Axis.AZM_RA, Axis.ALT_DEC)
            or length != cls._LENGTH
            or code not in cls._CODES
            or reply_length != cls._REPLY_LENGTH
        ):
            return None
        return cls._from_data(Axis(address), code, bytes(data))

    @classmethod
    @abstractmethod
    def _from_data(cls, axis: Axis, code: int, data: bytes) -> Self | None:
        """This command from its code and 3 data bytes, or None when they are not its shape."""

    @abstractmethod
    def _code_and_data(self) -> tuple[int, int, int, int]:
        """Its code and 3 data bytes."""

    def encode_payload(self) -> bytes:
        return bytes((self._LENGTH, self.axis, *self._code_and_data(), self._REPLY_LENGTH))


@dataclass(frozen=True, slots=True)
class VariableRateSlew(_AxisCommand):
    """``P 3 axis 6|7 hi lo 0 0``: slew one axis at a variable rate (quarter arcsec/s units)."""

    axis: Axis
    positive: bool
    rate_units: int

    changes_mount = True
    _LENGTH = 3
    _CODES = (_POSITIVE_VARIABLE, _NEGATIVE_VARIABLE)

    def __post_init__(self) -> None:
        check_range("rate_units", self.rate_units, 0, angles.MAX_RATE_UNITS)

    @classmethod
    def from_arcsec_per_second(cls, axis: Axis, arcsec_per_second: float) -> Self:
        """Slew at a signed rate in arcsec/s; the sign picks the direction."""
        return cls(axis, arcsec_per_second >= 0, angles.rate_to_units(arcsec_per_second))

    @classmethod
    def _from_data(cls, axis: Axis, code: int, data: bytes) -> Self | None:
        high, low, last = data
        return None if last else cls(axis, code == _POSITIVE_VARIABLE, (high << 8) | low)

    def _code_and_data(self) -> tuple[int, int, int, int]:
        high, low = angles.rate_units_to_bytes(self.rate_units)
        return (_POSITIVE_VARIABLE if self.positive else _NEGATIVE_VARIABLE), high, low, 0

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
class FixedRateSlew(_AxisCommand):
    """``P 2 axis 36|37 rate 0 0 0``: slew one axis at a hand-control speed 1-9; 0 stops."""

    axis: Axis
    positive: bool
    rate: int

    changes_mount = True
    _LENGTH = 2
    _CODES = (_POSITIVE_FIXED, _NEGATIVE_FIXED)

    def __post_init__(self) -> None:
        check_range("rate", self.rate, 0, _MAX_FIXED_RATE)

    @classmethod
    def _from_data(cls, axis: Axis, code: int, data: bytes) -> Self | None:
        rate, *rest = data
        if rate > _MAX_FIXED_RATE or any(rest):
            return None
        return cls(axis, code == _POSITIVE_FIXED, rate)

    def _code_and_data(self) -> tuple[int, int, int, int]:
        return (_POSITIVE_FIXED if self.positive else _NEGATIVE_FIXED), self.rate, 0, 0

    def describe(self) -> str:
        if self.rate == 0:
            return f"stop {self.axis.label} (fixed rate 0)"
        sign = "+" if self.positive else "-"
        return f"slew {self.axis.label} {sign} at fixed rate {self.rate}"


@dataclass(frozen=True, slots=True)
class GetDeviceVersion(_AxisCommand):
    """``P 1 axis 254 0 0 0 2``: read a motor controller's firmware version."""

    axis: Axis

    _LENGTH = 1
    _CODES = (_GET_VERSION,)
    _REPLY_LENGTH = 2

    @classmethod
    def _from_data(cls, axis: Axis, code: int, data: bytes) -> Self | None:
        return None if any(data) else cls(axis)

    def _code_and_data(self) -> tuple[int, int, int, int]:
        return _GET_VERSION, 0, 0, 0

    def success_reply(self, data: bytes) -> Reply:
        return DeviceVersion(data[0], data[1])

    def describe(self) -> str:
        return f"get {self.axis.label} motor controller version"


@dataclass(frozen=True, slots=True)
class _AxisPositionCommand(_AxisCommand):
    """Shared shape of the passthrough commands that carry one 24-bit axis position."""

    axis: Axis
    position: int

    changes_mount = True
    _LENGTH = 4
    _VERB: ClassVar[str] = ""

    def __post_init__(self) -> None:
        check_range("position", self.position, 0, angles.POSITION24_UNITS - 1)

    @classmethod
    def from_degrees(cls, axis: Axis, degrees: float) -> Self:
        """From an axis angle in degrees (wrapped, rounded to the 24-bit step)."""
        return cls(axis, angles.degrees_to_position24(degrees))

    @classmethod
    def _from_data(cls, axis: Axis, code: int, data: bytes) -> Self | None:
        return cls(axis, angles.bytes_to_position24(*data))

    def _code_and_data(self) -> tuple[int, int, int, int]:
        return self._CODES[0], *angles.position24_to_bytes(self.position)

    @property
    def degrees(self) -> float:
        """The axis angle in degrees, [0, 360)."""
        return angles.position24_to_degrees(self.position)

    def describe(self) -> str:
        return f"{self._VERB} {self.axis.label} to {self.degrees:.4f}°"


class SlowGoto(_AxisPositionCommand):
    """``P 4 axis 23 h m l 0``: slow goto of one axis to a 24-bit position."""

    __slots__ = ()
    _CODES = (_SLOW_GOTO,)
    _VERB = "slow goto"


class SetAxisPosition(_AxisPositionCommand):
    """``P 4 axis 4 h m l 0``: redefine one axis's current position (24-bit)."""

    __slots__ = ()
    _CODES = (_SET_POSITION,)
    _VERB = "set position of"


TYPED_PASSTHROUGH: Final[tuple[type[PassthroughCommand], ...]] = (
    VariableRateSlew,
    FixedRateSlew,
    GetDeviceVersion,
    SlowGoto,
    SetAxisPosition,
)
"""The passthrough commands with a typed payload; a payload none of them takes is `Passthrough`."""


def _typed(payload: bytes) -> PassthroughCommand | None:
    for typed in TYPED_PASSTHROUGH:
        command = typed.from_payload(payload)
        if command is not None:
            return command
    return None


@dataclass(frozen=True, slots=True)
class Passthrough(PassthroughCommand):
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
        typed = _typed(self.payload)
        if typed is not None:
            raise ValueError(f"payload {self.payload.hex(' ')} is {type(typed).__name__}; use that")

    @classmethod
    def from_payload(cls, payload: bytes) -> Self | None:
        return None if _typed(payload) is not None else cls(payload)

    def encode_payload(self) -> bytes:
        return self.payload

    def success_reply(self, data: bytes) -> Reply:
        return PassthroughReply(data)

    def describe(self) -> str:
        return f"passthrough {self.payload.hex(' ').upper()} (reply {self.reply_length} bytes)"


def passthrough_command(payload: bytes) -> PassthroughCommand:
    """The typed command for a 7-byte ``P`` payload, or `Passthrough` when none fits."""
    return _typed(payload) or Passthrough(payload)
