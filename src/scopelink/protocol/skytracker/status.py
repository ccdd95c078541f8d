"""The Sky Tracker's ``R`` status byte: mode flags (spec Table 1) and pressed directions.

High nibble, spec Table 1: B7 UTIL, B6 CUT, B5 SPEED, B4 GOTO. Low nibble (missing from the spec;
project decision in NOTES.md): B3 up, B2 down, B1 left, B0 right pressed, by the PC or the hand box.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass


class ModeFlag(enum.IntFlag):
    """High-nibble bits of the status byte, named as in the spec's Table 1."""

    UTIL = 0x80
    CUT = 0x40
    SPEED = 0x20
    GOTO = 0x10


class Direction(enum.IntFlag):
    """Low-nibble bits of the status byte: a direction button held down."""

    UP = 0x08
    DOWN = 0x04
    LEFT = 0x02
    RIGHT = 0x01


NO_DIRECTION = Direction(0)


class TrackerMode(enum.Enum):
    """The five modes of Table 1; the value is the command letter that selects the mode."""

    UTILITY = "U"
    TRACK = "T"
    GUIDE = "D"
    STANDBY = "B"
    GOTO = "G"


MODE_FLAGS: dict[TrackerMode, ModeFlag] = {
    TrackerMode.UTILITY: ModeFlag.UTIL,
    TrackerMode.TRACK: ModeFlag(0),
    TrackerMode.GUIDE: ModeFlag.SPEED,
    TrackerMode.STANDBY: ModeFlag.CUT,
    TrackerMode.GOTO: ModeFlag.GOTO,
}
_MODE_OF_FLAGS = {flags: mode for mode, flags in MODE_FLAGS.items()}

MODE_MEANINGS: dict[TrackerMode, str] = {
    TrackerMode.UTILITY: "slew fast with the arrows, up to 4°/s",
    TrackerMode.TRACK: "tracking; arrows move 8 arcmin/s",
    TrackerMode.GUIDE: "tracking; arrows move at the guide speed",
    TrackerMode.STANDBY: "motor drive cut to save battery",
    TrackerMode.GOTO: "slewing to the Sky Commander's current object",
}

_DIRECTION_ORDER = (Direction.UP, Direction.DOWN, Direction.LEFT, Direction.RIGHT)
_MODE_FLAG_ORDER = (ModeFlag.UTIL, ModeFlag.CUT, ModeFlag.SPEED, ModeFlag.GOTO)


def direction_names(directions: Direction) -> str:
    """``"up+left"`` style names of the directions in ``directions``; ``"none"`` when empty."""
    names = [str(d.name).lower() for d in _DIRECTION_ORDER if d in directions]
    return "+".join(names) if names else "none"


@dataclass(frozen=True, slots=True)
class TrackerStatus:
    """One status byte. Every byte value is representable; odd flag mixes keep their raw bits."""

    flags: ModeFlag
    directions: Direction = NO_DIRECTION

    @classmethod
    def for_mode(cls, mode: TrackerMode, directions: Direction = NO_DIRECTION) -> TrackerStatus:
        """The status a Sky Tracker reports in ``mode`` with ``directions`` pressed."""
        return cls(MODE_FLAGS[mode], directions)

    @classmethod
    def from_byte(cls, value: int) -> TrackerStatus:
        """Decode a status byte (0-255); never raises for a byte value."""
        if not 0 <= value <= 0xFF:
            raise ValueError(f"a status byte is 0-255, got {value}")
        return cls(ModeFlag(value & 0xF0), Direction(value & 0x0F))

    def to_byte(self) -> int:
        """The status byte."""
        return (int(self.flags) & 0xF0) | (int(self.directions) & 0x0F)

    @property
    def mode(self) -> TrackerMode | None:
        """The Table 1 mode these flags mean, or None for a combination the table does not list."""
        return _MODE_OF_FLAGS.get(self.flags)

    def describe(self) -> str:
        """E.g. ``"0x28: GUIDE (SPEED: tracking; arrows move at the guide speed); pressed: up"``."""
        flag_names = (
            "|".join(str(f.name) for f in _MODE_FLAG_ORDER if f in self.flags) or "no flags"
        )
        mode = self.mode
        if mode is None:
            mode_text = f"{flag_names} (not a mode of spec Table 1)"
        else:
            mode_text = f"{mode.name} ({flag_names}: {MODE_MEANINGS[mode]})"
        pressed = direction_names(self.directions)
        if (Direction.UP | Direction.DOWN) in self.directions or (
            Direction.LEFT | Direction.RIGHT
        ) in self.directions:
            pressed += " (opposite directions together)"
        return f"0x{self.to_byte():02X}: {mode_text}; pressed: {pressed}"

    def __str__(self) -> str:
        return self.describe()
