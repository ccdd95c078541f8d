"""Sky Commander commands (PC or Sky Tracker -> Sky Commander) and their replies."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import ClassVar, Self

from .calfloat import CALFLOAT_SIZE, decode_calfloat_pair, encode_calfloat_pair
from .coordinates import (
    check_dec_degrees,
    check_ra_hours,
    dec_text,
    format_dec_degrees,
    format_ra_hours,
    parse_dec_degrees,
    parse_ra_hours,
    ra_sexagesimal,
)
from .wire import Acknowledge, Command, Reply

TEMPORARY_SLOT = 99
"""``L99``: load into RAM and make current (for GOTO or realign)."""
STORED_SLOTS = range(59)
"""``L00``-``L58``: store in the Sky Commander's non-volatile memory; not made current."""

POSITION_REPLY_SIZE = 16
_POSITION_FIELDS = re.compile(rb" *([^\s\x00]+) +([^\s\x00]+)[ \x00]*")
_LOAD_LINE = re.compile(rb"L(\d\d) +(\S+) +(\S+) *\r")


def _check_slot(slot: int) -> None:
    if slot != TEMPORARY_SLOT and slot not in STORED_SLOTS:
        raise ValueError(f"object slot is 00-58 or 99, got {slot}")


# --- replies -------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class PositionReply(Reply):
    """Reply to ``\\r``: 16 bytes ``" HH.HHH ±DD.DDD\\0"``, where the telescope points (J2000)."""

    size: ClassVar[int] = POSITION_REPLY_SIZE
    ra_hours: float
    dec_degrees: float

    def __post_init__(self) -> None:
        check_ra_hours(self.ra_hours)
        check_dec_degrees(self.dec_degrees)

    @classmethod
    def decode(cls, data: bytes) -> Self:
        """Lenient about spacing, sign and decimals, as INDI's ``sscanf(" %g %g")`` is."""
        match = _POSITION_FIELDS.fullmatch(data)
        if match is None:
            raise ValueError(f"position is not ' HH.HHH ±DD.DDD\\0': {data!r}")
        ra_field, dec_field = (field.decode("ascii", "replace") for field in match.groups())
        return cls(parse_ra_hours(ra_field), parse_dec_degrees(dec_field))

    def encode(self) -> bytes:
        text = f" {format_ra_hours(self.ra_hours)} {format_dec_degrees(self.dec_degrees)}\0"
        return text.encode("ascii")

    def describe(self) -> str:
        return f"position RA {ra_sexagesimal(self.ra_hours)}, Dec {dec_text(self.dec_degrees)}"


@dataclass(frozen=True, slots=True)
class _FloatPairReply(Reply):
    """Two bias-128 floats, altitude first."""

    size: ClassVar[int] = 2 * CALFLOAT_SIZE
    unit: ClassVar[str]
    label: ClassVar[str]
    altitude: float
    azimuth: float

    def __post_init__(self) -> None:
        self.encode()  # refuses numbers the format cannot carry

    @classmethod
    def decode(cls, data: bytes) -> Self:
        return cls(*decode_calfloat_pair(data))

    def encode(self) -> bytes:
        return encode_calfloat_pair(self.altitude, self.azimuth)

    def describe(self) -> str:
        return (
            f"{self.label}: Alt {self.altitude:+.6g}{self.unit}, "
            f"Az {self.azimuth:+.6g}{self.unit} (+Alt up, +Az counter-clockwise)"
        )


@dataclass(frozen=True, slots=True)
class OffsetsReply(_FloatPairReply):
    """Reply to ``O``: Alt and Az offsets to the current object, degrees."""

    unit: ClassVar[str] = "°"
    label: ClassVar[str] = "offsets to current object"


@dataclass(frozen=True, slots=True)
class RatesReply(_FloatPairReply):
    """Reply to ``R``: Alt and Az drive rates, degrees per minute."""

    unit: ClassVar[str] = "°/min"
    label: ClassVar[str] = "drive rates"


# --- commands ------------------------------------------------------------------------------


class CommanderCommand(Command):
    """A command for the Sky Commander (through a bus grant, or on its own port)."""

    __slots__ = ()


@dataclass(frozen=True, slots=True)
class ReadPosition(CommanderCommand):
    """``\\r``: read RA/Dec (16-byte reply)."""

    reply: ClassVar[type[Reply] | None] = PositionReply

    def encode(self) -> bytes:
        return b"\r"

    def describe(self) -> str:
        return "CR: read position"


@dataclass(frozen=True, slots=True)
class LoadObject(CommanderCommand):
    """``Lnn HH.HHH ±DD.DDD\\r``: slot 99 makes the object current; 00-58 store it. Reply ``A``.

    The wire carries 3 decimals; values are rounded when encoded (see coordinates.py).
    """

    reply: ClassVar[type[Reply] | None] = Acknowledge
    slot: int
    ra_hours: float
    dec_degrees: float

    def __post_init__(self) -> None:
        _check_slot(self.slot)
        check_ra_hours(self.ra_hours)
        check_dec_degrees(self.dec_degrees)

    @classmethod
    def current(cls, ra_hours: float, dec_degrees: float) -> Self:
        """``L99``: make these coordinates the current object."""
        return cls(TEMPORARY_SLOT, ra_hours, dec_degrees)

    @classmethod
    def decode(cls, line: bytes) -> Self:
        """Parse one whole line including its ``\\r``; raise ``ValueError`` saying what is wrong."""
        match = _LOAD_LINE.fullmatch(line)
        if match is None:
            raise ValueError(f"not 'Lnn HH.HHH ±DD.DDD<CR>': {line!r}")
        slot, ra_field, dec_field = (field.decode("ascii", "replace") for field in match.groups())
        return cls(int(slot), parse_ra_hours(ra_field), parse_dec_degrees(dec_field))

    def encode(self) -> bytes:
        ra, dec = format_ra_hours(self.ra_hours), format_dec_degrees(self.dec_degrees)
        return f"L{self.slot:02d} {ra} {dec}\r".encode("ascii")

    def describe(self) -> str:
        where = "as current object" if self.slot == TEMPORARY_SLOT else f"into slot {self.slot}"
        return (
            f"L{self.slot:02d}: load RA {ra_sexagesimal(self.ra_hours)}, "
            f"Dec {dec_text(self.dec_degrees)} {where}"
        )


@dataclass(frozen=True, slots=True)
class Realign(CommanderCommand):
    """``N``: realign the encoders on the current object. No reply (see docs)."""

    reply: ClassVar[type[Reply] | None] = None

    def encode(self) -> bytes:
        return b"N"

    def describe(self) -> str:
        return "N: realign on the current object"


@dataclass(frozen=True, slots=True)
class ReadOffsets(CommanderCommand):
    """``O``: read Alt/Az offsets to the current object (8-byte reply)."""

    reply: ClassVar[type[Reply] | None] = OffsetsReply

    def encode(self) -> bytes:
        return b"O"

    def describe(self) -> str:
        return "O: read offsets to current object"


@dataclass(frozen=True, slots=True)
class ReadRates(CommanderCommand):
    """``R``: read Alt/Az drive rates (8-byte reply)."""

    reply: ClassVar[type[Reply] | None] = RatesReply

    def encode(self) -> bytes:
        return b"R"

    def describe(self) -> str:
        return "R: read drive rates"


SINGLE_BYTE_COMMANDS: dict[int, CommanderCommand] = {
    command.encode()[0]: command
    for command in (ReadPosition(), Realign(), ReadOffsets(), ReadRates())
}
"""Sky Commander commands that are one byte long, by that byte (``L`` lines are framed by CR)."""
