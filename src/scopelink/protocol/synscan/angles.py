"""SynScan number formats: revolution fractions, rate bytes and 24-bit axis positions.

Angles on the wire are fractions of a revolution. The standard commands carry 16 bits (4 hex
digits), the precise ones 32 bits (8 hex digits) of which only the top 24 are significant. Dec and
Alt below zero are the two's complement fraction (-90° is ``C0000000``)."""

from __future__ import annotations

from typing import Final

HASH: Final = 0x23
"""The ``#`` that ends every reply."""

STANDARD_UNITS: Final = 1 << 16
"""Units per revolution in the 4-hex-digit commands (``E``, ``R``, ``Z``, ``B``, ``S``)."""

PRECISE_UNITS: Final = 1 << 32
"""Units per revolution in the 8-hex-digit commands (``e``, ``r``, ``z``, ``b``, ``s``)."""

POSITION24_UNITS: Final = 1 << 24
"""Units per revolution of a passthrough axis position (slow goto, set position)."""

_SIGNIFICANT_PRECISE_BITS: Final = 24
_IGNORED_PRECISE_BITS: Final = 32 - _SIGNIFICANT_PRECISE_BITS

RATE_UNITS_PER_ARCSEC: Final = 4
"""A variable-rate slew carries the rate in quarter arcseconds per second."""

MAX_RATE_UNITS: Final = 0xFFFF

_HEX_DIGITS: Final = b"0123456789ABCDEFabcdef"


def units_per_revolution(precise: bool) -> int:
    """Wire units in one revolution: 2**32 for the precise commands, 2**16 otherwise."""
    return PRECISE_UNITS if precise else STANDARD_UNITS


def hex_width(precise: bool) -> int:
    """Number of hex digits of one angle: 8 for the precise commands, 4 otherwise."""
    return 8 if precise else 4


def degrees_to_units(degrees: float, precise: bool) -> int:
    """Degrees (any value, wrapped) to wire units, rounded to the nearest step.

    Precise values are rounded to 24 bits and the ignored low byte is 00, as the hand control sends
    it. Negative angles become the two's complement fraction."""
    if precise:
        steps = round(degrees / 360.0 * POSITION24_UNITS) % POSITION24_UNITS
        return steps << _IGNORED_PRECISE_BITS
    return round(degrees / 360.0 * STANDARD_UNITS) % STANDARD_UNITS


def units_to_degrees(units: int, precise: bool) -> float:
    """Wire units to degrees in [0, 360); the ignored low byte of a precise value is dropped."""
    if precise:
        return (units >> _IGNORED_PRECISE_BITS) / POSITION24_UNITS * 360.0
    return units / STANDARD_UNITS * 360.0


def units_to_signed_degrees(units: int, precise: bool) -> float:
    """Wire units read as a two's complement fraction: degrees in [-180, 180)."""
    degrees = units_to_degrees(units, precise)
    return degrees - 360.0 if degrees >= 180.0 else degrees


def fold_over_pole(degrees: float) -> tuple[float, bool]:
    """Fold a Dec or Alt in [-180, 180) into [-90, 90].

    A declination read back above 90° means the axis went over the pole (100° is 80° seen from the
    other side). Returns the folded angle and whether folding happened ("flipped")."""
    if degrees > 90.0:
        return 180.0 - degrees, True
    if degrees < -90.0:
        return -180.0 - degrees, True
    return degrees, False


def hours_to_degrees(hours: float) -> float:
    """Hours of right ascension to degrees."""
    return hours * 15.0


def degrees_to_hours(degrees: float) -> float:
    """Degrees to hours of right ascension."""
    return degrees / 15.0


def format_hex_angle(units: int, precise: bool) -> bytes:
    """One angle as uppercase hex digits, 8 for precise values and 4 otherwise."""
    return b"%0*X" % (hex_width(precise), units)


def hex_digit_value(byte: int) -> int | None:
    """Value of one ASCII hex digit (either case), or None when the byte is not one."""
    if byte not in _HEX_DIGITS:
        return None
    return int(chr(byte), 16)


def is_hex_digit(byte: int) -> bool:
    """Whether the byte is an ASCII hex digit, upper or lower case."""
    return byte in _HEX_DIGITS


def rate_to_units(arcsec_per_second: float) -> int:
    """A slew rate magnitude (arcsec/s) to quarter arcsec/s units, rounded; the sign is dropped."""
    units = round(abs(arcsec_per_second) * RATE_UNITS_PER_ARCSEC)
    if units > MAX_RATE_UNITS:
        raise ValueError(
            f"rate {arcsec_per_second} arcsec/s is above the protocol's maximum "
            f"{MAX_RATE_UNITS / RATE_UNITS_PER_ARCSEC} arcsec/s"
        )
    return units


def units_to_rate(units: int) -> float:
    """Quarter arcsec/s units to arcsec/s."""
    return units / RATE_UNITS_PER_ARCSEC


def rate_units_to_bytes(units: int) -> tuple[int, int]:
    """Rate units to the (high, low) bytes of a variable-rate slew: 600 -> (2, 88)."""
    return units >> 8, units & 0xFF


def degrees_to_position24(degrees: float) -> int:
    """Degrees (wrapped) to a 24-bit axis position, rounded: 220° -> 10,252,743."""
    return round(degrees / 360.0 * POSITION24_UNITS) % POSITION24_UNITS


def position24_to_degrees(position: int) -> float:
    """A 24-bit axis position to degrees in [0, 360)."""
    return position / POSITION24_UNITS * 360.0


def position24_to_bytes(position: int) -> tuple[int, int, int]:
    """A 24-bit position to its (high, middle, low) bytes: 10,252,743 -> (156, 113, 199)."""
    return (position >> 16) & 0xFF, (position >> 8) & 0xFF, position & 0xFF


def bytes_to_position24(high: int, middle: int, low: int) -> int:
    """The (high, middle, low) bytes of a 24-bit position to its value."""
    return (high << 16) | (middle << 8) | low


def format_hours(hours: float) -> str:
    """Hours as ``4h 57m 12.3s`` (wrapped into [0, 24))."""
    tenths = round((hours % 24.0) * 36000.0) % (24 * 36000)
    whole_hours, tenths = divmod(tenths, 36000)
    minutes, tenths = divmod(tenths, 600)
    return f"{whole_hours}h {minutes:02d}m {tenths / 10:04.1f}s"


def format_signed_degrees(degrees: float) -> str:
    """Degrees with a sign and two decimals: ``+26.44°``."""
    return f"{degrees:+.2f}°"


def format_degrees(degrees: float) -> str:
    """Degrees with two decimals, no sign: ``26.25°``."""
    return f"{degrees:.2f}°"
