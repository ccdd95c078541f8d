"""Sky Tracker commands (PC -> Sky Tracker) and their replies, as typed messages."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Self

from .calfloat import CALFLOAT_SIZE, decode_calfloat_pair, encode_calfloat_pair
from .calibration import bearing_diameter_in, ground_board_diameter_in
from .status import Direction, TrackerMode, TrackerStatus, direction_names
from .wire import Acknowledge, Command, Reply

DEFAULT_GUIDE_SPEED_ARCSEC_PER_S = 120
"""Guide speed on both axes after power-on (spec, ``K``)."""

VERSION_LENGTH = 8


def _check_guide_speed(value: int, axis: str) -> None:
    if not 0 <= value <= 0xFF:
        raise ValueError(f"{axis} guide speed is 0-255 arcsec/s, got {value}")


def _describe_factor(factor: float, size_of: str, diameter_in: float | None) -> str:
    size = f"{diameter_in:.2f} in {size_of}" if diameter_in is not None else f"no {size_of}"
    return f"{factor:g} ({size})"


def _calibration_text(azimuth_factor: float, elevation_factor: float) -> str:
    azimuth_size = ground_board_diameter_in(azimuth_factor) if azimuth_factor > 0 else None
    elevation_size = bearing_diameter_in(elevation_factor) if elevation_factor > 0 else None
    return (
        f"azimuth factor {_describe_factor(azimuth_factor, 'ground board', azimuth_size)}, "
        f"elevation factor {_describe_factor(elevation_factor, 'el bearing', elevation_size)}"
    )


# --- replies -------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class StatusReply(Reply):
    """Reply to ``R``: the status byte."""

    size: ClassVar[int] = 1
    status: TrackerStatus

    @classmethod
    def decode(cls, data: bytes) -> Self:
        return cls(TrackerStatus.from_byte(data[0]))

    def encode(self) -> bytes:
        return bytes([self.status.to_byte()])

    def describe(self) -> str:
        return f"status {self.status.describe()}"


@dataclass(frozen=True, slots=True)
class CalibrationReply(Reply):
    """Reply to ``s``: azimuth then elevation calibration factor, two bias-128 floats."""

    size: ClassVar[int] = 2 * CALFLOAT_SIZE
    azimuth_factor: float
    elevation_factor: float

    def __post_init__(self) -> None:
        self.encode()  # refuses numbers the format cannot carry

    @classmethod
    def decode(cls, data: bytes) -> Self:
        return cls(*decode_calfloat_pair(data))

    def encode(self) -> bytes:
        return encode_calfloat_pair(self.azimuth_factor, self.elevation_factor)

    def describe(self) -> str:
        return f"calibration: {_calibration_text(self.azimuth_factor, self.elevation_factor)}"


@dataclass(frozen=True, slots=True)
class VersionReply(Reply):
    """Reply to ``V``: always eight ASCII characters, e.g. ``'v4.0    '``."""

    size: ClassVar[int] = VERSION_LENGTH
    text: str

    def __post_init__(self) -> None:
        if len(self.text) != VERSION_LENGTH or not self.text.isascii():
            raise ValueError(f"a version is {VERSION_LENGTH} ASCII characters, got {self.text!r}")

    @classmethod
    def decode(cls, data: bytes) -> Self:
        if not data.isascii():
            raise ValueError(f"version is not ASCII: {data!r}")
        return cls(data.decode("ascii"))

    @classmethod
    def padded(cls, version: str) -> Self:
        """The reply for ``version`` (e.g. ``"v4.0"``), padded with spaces to eight characters."""
        return cls(version.ljust(VERSION_LENGTH))

    def encode(self) -> bytes:
        return self.text.encode("ascii")

    def describe(self) -> str:
        return f"firmware version {self.text!r}"


@dataclass(frozen=True, slots=True)
class GuideSpeedReply(Reply):
    """Reply to ``k``: azimuth and elevation guide speeds, arcsec/s (0-255)."""

    size: ClassVar[int] = 2
    azimuth_arcsec_per_s: int
    elevation_arcsec_per_s: int

    def __post_init__(self) -> None:
        _check_guide_speed(self.azimuth_arcsec_per_s, "azimuth")
        _check_guide_speed(self.elevation_arcsec_per_s, "elevation")

    @classmethod
    def decode(cls, data: bytes) -> Self:
        return cls(data[0], data[1])

    def encode(self) -> bytes:
        return bytes([self.azimuth_arcsec_per_s, self.elevation_arcsec_per_s])

    def describe(self) -> str:
        return (
            f"guide speed: azimuth {self.azimuth_arcsec_per_s} arcsec/s, "
            f"elevation {self.elevation_arcsec_per_s} arcsec/s"
        )


@dataclass(frozen=True, slots=True)
class BusAnswer(Reply):
    """Reply to ``Q``: ``A`` grants the Sky Commander bus, NUL refuses it (a GOTO is running)."""

    size: ClassVar[int] = 1
    granted: bool

    @classmethod
    def decode(cls, data: bytes) -> Self:
        if data == b"A":
            return cls(granted=True)
        if data == b"\x00":
            return cls(granted=False)
        raise ValueError(f"expected bus grant 'A' or refusal NUL, got {data!r}")

    def encode(self) -> bytes:
        return b"A" if self.granted else b"\x00"

    def describe(self) -> str:
        if self.granted:
            return "A: bus granted (bytes now relayed to the Sky Commander until 'q')"
        return "NUL: bus refused (GOTO running)"


# --- commands ------------------------------------------------------------------------------


class TrackerCommand(Command):
    """A command for the Sky Tracker itself (sent while the bus is not held)."""

    __slots__ = ()


@dataclass(frozen=True, slots=True)
class SelectMode(TrackerCommand):
    """``U``/``T``/``D``/``B``/``G``: enter a mode; U, T, D or B during a GOTO abort it."""

    reply: ClassVar[type[Reply] | None] = None
    mode: TrackerMode

    def encode(self) -> bytes:
        return self.mode.value.encode("ascii")

    def describe(self) -> str:
        return f"{self.mode.value}: enter {self.mode.name} mode"


DIRECTION_LETTERS: dict[Direction, bytes] = {
    Direction.UP: b"u",
    Direction.DOWN: b"d",
    Direction.LEFT: b"l",
    Direction.RIGHT: b"r",
}


@dataclass(frozen=True, slots=True)
class PressDirection(TrackerCommand):
    """``u``/``d``/``l``/``r``: press one direction button (releases the opposite one)."""

    reply: ClassVar[type[Reply] | None] = None
    direction: Direction

    def __post_init__(self) -> None:
        if self.direction not in DIRECTION_LETTERS:
            raise ValueError(f"press exactly one direction, got {self.direction!r}")

    def encode(self) -> bytes:
        return DIRECTION_LETTERS[self.direction]

    def describe(self) -> str:
        return f"{self.encode().decode()}: press {direction_names(self.direction)}"


@dataclass(frozen=True, slots=True)
class ReleaseDirections(TrackerCommand):
    """``b``: release all direction buttons."""

    reply: ClassVar[type[Reply] | None] = None

    def encode(self) -> bytes:
        return b"b"

    def describe(self) -> str:
        return "b: release all directions"


@dataclass(frozen=True, slots=True)
class ReadStatus(TrackerCommand):
    """``R``: read mode flags and pressed directions (1-byte reply)."""

    reply: ClassVar[type[Reply] | None] = StatusReply

    def encode(self) -> bytes:
        return b"R"

    def describe(self) -> str:
        return "R: read status"


@dataclass(frozen=True, slots=True)
class SetCalibration(TrackerCommand):
    """``S`` + 8 bytes: store calibration factors (reply ``A``; only as the first command after
    power-on, once)."""

    reply: ClassVar[type[Reply] | None] = Acknowledge
    azimuth_factor: float
    elevation_factor: float

    def __post_init__(self) -> None:
        self.encode()  # refuses numbers the format cannot carry

    def encode(self) -> bytes:
        return b"S" + encode_calfloat_pair(self.azimuth_factor, self.elevation_factor)

    def describe(self) -> str:
        return f"S: set {_calibration_text(self.azimuth_factor, self.elevation_factor)}"


@dataclass(frozen=True, slots=True)
class ReadCalibration(TrackerCommand):
    """``s``: read the calibration factors (8-byte reply)."""

    reply: ClassVar[type[Reply] | None] = CalibrationReply

    def encode(self) -> bytes:
        return b"s"

    def describe(self) -> str:
        return "s: read calibration"


@dataclass(frozen=True, slots=True)
class ReadVersion(TrackerCommand):
    """``V``: read the firmware version (8 ASCII characters)."""

    reply: ClassVar[type[Reply] | None] = VersionReply

    def encode(self) -> bytes:
        return b"V"

    def describe(self) -> str:
        return "V: read version"


@dataclass(frozen=True, slots=True)
class SetGuideSpeed(TrackerCommand):
    """``K`` + 2 bytes: azimuth and elevation guide speeds in arcsec/s. No reply (see docs)."""

    reply: ClassVar[type[Reply] | None] = None
    azimuth_arcsec_per_s: int
    elevation_arcsec_per_s: int

    def __post_init__(self) -> None:
        _check_guide_speed(self.azimuth_arcsec_per_s, "azimuth")
        _check_guide_speed(self.elevation_arcsec_per_s, "elevation")

    def encode(self) -> bytes:
        return b"K" + bytes([self.azimuth_arcsec_per_s, self.elevation_arcsec_per_s])

    def describe(self) -> str:
        return (
            f"K: set guide speed azimuth {self.azimuth_arcsec_per_s} arcsec/s, "
            f"elevation {self.elevation_arcsec_per_s} arcsec/s"
        )


@dataclass(frozen=True, slots=True)
class ReadGuideSpeed(TrackerCommand):
    """``k``: read the guide speeds (2-byte reply)."""

    reply: ClassVar[type[Reply] | None] = GuideSpeedReply

    def encode(self) -> bytes:
        return b"k"

    def describe(self) -> str:
        return "k: read guide speed"


@dataclass(frozen=True, slots=True)
class RequestBus(TrackerCommand):
    """``Q``: ask for the Sky Commander bus (reply ``A`` granted or NUL refused)."""

    reply: ClassVar[type[Reply] | None] = BusAnswer

    def encode(self) -> bytes:
        return b"Q"

    def describe(self) -> str:
        return "Q: request the Sky Commander bus"


@dataclass(frozen=True, slots=True)
class ReleaseBus(TrackerCommand):
    """``q``: end a bus grant; the Sky Tracker does not relay it."""

    reply: ClassVar[type[Reply] | None] = None

    def encode(self) -> bytes:
        return b"q"

    def describe(self) -> str:
        return "q: release the Sky Commander bus"


@dataclass(frozen=True, slots=True)
class RelayToCommander:
    """Device side only: bytes received while the bus is granted, to pass to the Sky Commander."""

    data: bytes

    def describe(self) -> str:
        return f"relay to Sky Commander: {self.data!r}"

    def __str__(self) -> str:
        return self.describe()


SINGLE_BYTE_COMMANDS: dict[int, TrackerCommand] = {
    command.encode()[0]: command
    for command in (
        *(SelectMode(mode) for mode in TrackerMode),
        *(PressDirection(direction) for direction in DIRECTION_LETTERS),
        ReleaseDirections(),
        ReadStatus(),
        ReadCalibration(),
        ReadVersion(),
        ReadGuideSpeed(),
        RequestBus(),
        ReleaseBus(),
    )
}
"""Commands that are one byte long, by that byte."""

PAYLOAD_SIZES: dict[int, int] = {ord("S"): 2 * CALFLOAT_SIZE, ord("K"): 2}
"""Commands followed by a fixed-length payload: payload bytes after the command letter."""


def decode_payload_command(code: int, payload: bytes) -> TrackerCommand:
    """Build ``S`` or ``K`` from its payload (never fails: every payload byte value is valid)."""
    if code == ord("S"):
        return SetCalibration(*decode_calfloat_pair(payload))
    return SetGuideSpeed(payload[0], payload[1])
