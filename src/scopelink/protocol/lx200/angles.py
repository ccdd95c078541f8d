"""The sexagesimal forms LX200 uses on the wire, in both precisions.

High precision (the default here, and what INDI and Stellarium switch to) gives RA as
``HH:MM:SS`` and Dec as ``sDD*MM:SS``; low precision gives ``HH:MM.T`` (tenths of a minute) and
``sDD*MM``. ``*`` stands for the degree sign, which is Meade's byte 0xDF unless the caller asks
for the ASCII ``*`` (:data:`MEADE_DEGREE_SIGN`, :data:`ASTERISK_DEGREE_SIGN`). Altitude and
azimuth use Meade's ``'`` before the seconds. Every value is rounded once, to the last digit
shown, so 59.6 s never prints as 60.

Parsing is lenient in what it accepts, as every LX200 clone is: any of ``* : ' °`` (and Meade's
0xDF degree sign, read as Latin-1) between the fields, an optional sign, optional spaces, and an
optional decimal fraction on the last field.
"""

from __future__ import annotations

import math
import re
from typing import Final

__all__ = [
    "ASTERISK_DEGREE_SIGN",
    "DEGREE_SIGN",
    "MEADE_DEGREE_SIGN",
    "degree_sign_of",
    "format_altitude",
    "format_azimuth",
    "format_dec",
    "format_ra",
    "format_signed_degrees_minutes",
    "parse_sexagesimal",
    "precision_of",
]

MEADE_DEGREE_SIGN: Final = "\xdf"
"""Byte 0xDF (read as Latin-1): the degree sign Meade's handsets send, and the one Stellarium's
LX200 driver checks for (it writes it in its own ``:Sd``)."""
ASTERISK_DEGREE_SIGN: Final = "*"
"""The ASCII stand-in Meade's manual prints and SkySafari writes (``:St+37*17#``)."""
DEGREE_SIGN: Final = MEADE_DEGREE_SIGN
"""What a connection is answered with before it writes a degree sign of its own: Meade's byte,
which Stellarium requires and INDI (any separator) and SkySafari (real Meade handsets) read."""

_FIELDS = re.compile(
    r"^\s*(?P<sign>[+-])?\s*(?P<a>\d{1,3})"
    r"(?:\s*[*:'\xdf\xb0 ]\s*(?P<b>\d{1,2}(?:\.\d+)?)"
    r"(?:\s*[:'\" ]\s*(?P<c>\d{1,2}(?:\.\d+)?))?)?\s*$"
)


def degree_sign_of(text: str) -> str | None:
    """The degree sign a client wrote after the degrees in ``text`` (``sDD*MM...``): 0xDF or
    ``*``; None when it wrote another separator (INDI's ``:``) or none."""
    match = re.match(r"\s*[+-]?\s*\d{1,3}\s*([*\xdf])", text)
    return None if match is None else match[1]


def precision_of(text: str) -> bool | None:
    """True when ``text`` has seconds (high precision: ``HH:MM:SS``, ``sDD*MM:SS``), False when
    it stops at minutes (low: ``HH:MM.T``, ``sDD*MM``), None when it is not sexagesimal."""
    match = _FIELDS.match(text)
    if match is None or match["b"] is None:
        return None
    return match["c"] is not None


def parse_sexagesimal(text: str) -> float | None:
    """``[s]A[sepB[sepC]]`` -> A + B/60 + C/3600 with the sign; None if it is not that shape.

    Minutes and seconds must be below 60; the caller checks the range of the whole value.
    """
    match = _FIELDS.match(text)
    if match is None:
        return None
    minutes = float(match["b"]) if match["b"] is not None else 0.0
    seconds = float(match["c"]) if match["c"] is not None else 0.0
    if minutes >= 60.0 or seconds >= 60.0:
        return None
    if match["c"] is not None and "." in (match["b"] or ""):
        return None  # a fraction of a minute and then seconds: not a number
    value = int(match["a"]) + minutes / 60.0 + seconds / 3600.0
    return -value if match["sign"] == "-" else value


def _check(value: float, what: str) -> None:
    if not math.isfinite(value):
        raise ValueError(f"{what} {value} is not a number")


def format_ra(ra_hours: float, *, high_precision: bool = True) -> str:
    """``HH:MM:SS`` or ``HH:MM.T``, wrapped into [0, 24 h)."""
    _check(ra_hours, "right ascension")
    if high_precision:
        total = round(ra_hours * 3600.0) % 86400
        return f"{total // 3600:02d}:{total // 60 % 60:02d}:{total % 60:02d}"
    tenths = round(ra_hours * 600.0) % 14400
    return f"{tenths // 600:02d}:{tenths // 10 % 60:02d}.{tenths % 10:d}"


def _signed(value_deg: float, high_precision: bool, seconds_separator: str, degree: str) -> str:
    limit_deg = 90
    if high_precision:
        total = min(round(abs(value_deg) * 3600.0), limit_deg * 3600)
        sign = "-" if value_deg < 0 and total else "+"
        return (
            f"{sign}{total // 3600:02d}{degree}{total // 60 % 60:02d}"
            f"{seconds_separator}{total % 60:02d}"
        )
    total = min(round(abs(value_deg) * 60.0), limit_deg * 60)
    sign = "-" if value_deg < 0 and total else "+"
    return f"{sign}{total // 60:02d}{degree}{total % 60:02d}"


def format_dec(
    dec_deg: float, *, high_precision: bool = True, degree_sign: str = DEGREE_SIGN
) -> str:
    """``sDD*MM:SS`` or ``sDD*MM`` (clamped to ±90°)."""
    _check(dec_deg, "declination")
    return _signed(dec_deg, high_precision, ":", degree_sign)


def format_altitude(
    alt_deg: float, *, high_precision: bool = True, degree_sign: str = DEGREE_SIGN
) -> str:
    """``sDD*MM'SS`` or ``sDD*MM`` (clamped to ±90°)."""
    _check(alt_deg, "altitude")
    return _signed(alt_deg, high_precision, "'", degree_sign)


def format_azimuth(
    az_deg: float, *, high_precision: bool = True, degree_sign: str = DEGREE_SIGN
) -> str:
    """``DDD*MM'SS`` or ``DDD*MM``, wrapped into [0, 360°)."""
    _check(az_deg, "azimuth")
    if high_precision:
        total = round(az_deg * 3600.0) % (360 * 3600)
        return f"{total // 3600:03d}{degree_sign}{total // 60 % 60:02d}'{total % 60:02d}"
    total = round(az_deg * 60.0) % (360 * 60)
    return f"{total // 60:03d}{degree_sign}{total % 60:02d}"


def format_signed_degrees_minutes(
    value_deg: float, *, degree_digits: int = 2, degree_sign: str = DEGREE_SIGN
) -> str:
    """``sDD*MM`` (latitude) or, with ``degree_digits=3``, ``sDDD*MM`` (longitude)."""
    _check(value_deg, "angle")
    total = round(abs(value_deg) * 60.0)
    sign = "-" if value_deg < 0 and total else "+"
    return f"{sign}{total // 60:0{degree_digits}d}{degree_sign}{total % 60:02d}"
