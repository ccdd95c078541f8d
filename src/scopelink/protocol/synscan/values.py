"""The small value types of the SynScan wire: axes, frames, tracking modes, dialects, and the
range checks and wording the messages share."""

from __future__ import annotations

from enum import Enum, IntEnum, StrEnum

from scopelink.protocol.synscan import angles


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


class VersionDialect(Enum):
    """How a ``V`` reply is shaped."""

    SYNSCAN_HEX = "SynScan: 6 uppercase hex digits + #"
    NEXSTAR_BINARY = "Celestron NexStar: 2 binary bytes + #"
    SYNSCAN_BINARY = "old SynScan: 3 binary bytes + #"


class PointingSide(StrEnum):
    """The ``p`` reply: 'E' is not flipped in the northern hemisphere, 'W' flipped (reversed
    south)."""

    EAST = "E"
    WEST = "W"


_TRACKING_NAMES: dict[int, str] = {
    Tracking.OFF: "off",
    Tracking.ALT_AZ: "alt-az",
    Tracking.EQUATORIAL: "equatorial",
    Tracking.PEC: "equatorial with PEC",
}


def check_range(name: str, value: int, low: int, high: int) -> None:
    """Refuse ``value`` outside ``low..high`` with a one-line `ValueError` naming it."""
    if not low <= value <= high:
        raise ValueError(f"{name} must be in {low}..{high}, got {value}")


def check_byte(name: str, value: int) -> None:
    """Refuse a value that does not fit one byte."""
    check_range(name, value, 0, 0xFF)


def check_units(name: str, units: int, precise: bool) -> None:
    """Refuse wire units outside one revolution of the given precision."""
    check_range(name, units, 0, angles.units_per_revolution(precise) - 1)


def precision_word(precise: bool) -> str:
    """``"precise "`` or nothing, to start a description."""
    return "precise " if precise else ""


def describe_tracking(mode: int) -> str:
    """A tracking mode byte with its name."""
    return f"{mode} ({_TRACKING_NAMES.get(mode, 'unknown')})"


def describe_byte(value: int) -> str:
    """A byte in hex, with its character when printable."""
    printable = chr(value) if 0x20 <= value < 0x7F else None
    return f"0x{value:02X} ({printable!r})" if printable else f"0x{value:02X}"


def describe_ra_dec(ra_units: int, dec_units: int, precise: bool) -> str:
    """RA/Dec wire units in words (Dec folded over the pole when beyond ±90°)."""
    ra_hours = angles.degrees_to_hours(angles.units_to_degrees(ra_units, precise))
    dec, flipped = angles.fold_over_pole(angles.units_to_signed_degrees(dec_units, precise))
    pole = " (over the pole)" if flipped else ""
    return f"RA {angles.format_hours(ra_hours)}, Dec {angles.format_signed_degrees(dec)}{pole}"


def describe_az_alt(az_units: int, alt_units: int, precise: bool) -> str:
    """Az/Alt wire units in words (Alt folded over the zenith when beyond ±90°)."""
    az = angles.units_to_degrees(az_units, precise)
    alt, flipped = angles.fold_over_pole(angles.units_to_signed_degrees(alt_units, precise))
    over = " (over the zenith)" if flipped else ""
    return f"Az {angles.format_degrees(az)}, Alt {angles.format_signed_degrees(alt)}{over}"


def ra_dec_units(ra_hours: float, dec_degrees: float, precise: bool) -> tuple[int, int]:
    """RA in hours and Dec in degrees as wire units (negative Dec as two's complement)."""
    return (
        angles.degrees_to_units(angles.hours_to_degrees(ra_hours), precise),
        angles.degrees_to_units(dec_degrees, precise),
    )
