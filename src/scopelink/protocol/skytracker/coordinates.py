"""Sky Commander coordinate text: RA in decimal hours ``HH.HHH``, Dec in degrees ``±DD.DDD``.

Coordinates are J2000 (project decision, NOTES.md). Three decimals: 0.001 h = 3.6 s of RA,
0.001° = 3.6 arcsec of Dec.
"""

from __future__ import annotations

import math
import re

RA_TEXT_LENGTH = 6
DEC_TEXT_LENGTH = 7
_DECIMALS = 3

_RA_PATTERN = re.compile(r"\d{1,2}(?:\.\d*)?")
_DEC_PATTERN = re.compile(r"[+-]?\d{1,2}(?:\.\d*)?")


class CoordinateRangeError(ValueError):
    """RA outside [0, 24) h or Dec outside [-90, +90]°, or not a number."""


def check_ra_hours(ra_hours: float) -> float:
    """Return ``ra_hours`` if it is a finite RA in [0, 24); raise :class:`CoordinateRangeError`."""
    if not (math.isfinite(ra_hours) and 0.0 <= ra_hours < 24.0):
        raise CoordinateRangeError(f"RA must be in [0, 24) hours, got {ra_hours!r}")
    return ra_hours


def check_dec_degrees(dec_degrees: float) -> float:
    """Return ``dec_degrees`` if it is a finite Dec in [-90, +90]; raise otherwise."""
    if not (math.isfinite(dec_degrees) and -90.0 <= dec_degrees <= 90.0):
        raise CoordinateRangeError(f"Dec must be in [-90, +90] degrees, got {dec_degrees!r}")
    return dec_degrees


def format_ra_hours(ra_hours: float) -> str:
    """``"HH.HHH"`` to the nearest 0.001 h; 23.9996 h rounds to 24.000, which wraps to 00.000."""
    text = f"{check_ra_hours(ra_hours):06.{_DECIMALS}f}"
    return "00.000" if text == "24.000" else text


def format_dec_degrees(dec_degrees: float) -> str:
    """``"±DD.DDD"``, rounded to the nearest 0.001°, always signed; zero is ``+00.000``."""
    text = f"{check_dec_degrees(dec_degrees):+07.{_DECIMALS}f}"
    return "+00.000" if text == "-00.000" else text


def parse_ra_hours(text: str) -> float:
    """Parse decimal hours leniently (1-2 integer digits, any decimals); 24 exactly folds to 0."""
    if _RA_PATTERN.fullmatch(text) is None:
        raise CoordinateRangeError(f"RA is not decimal hours: {text!r}")
    value = float(text)
    if value == 24.0:
        return 0.0
    return check_ra_hours(value)


def parse_dec_degrees(text: str) -> float:
    """Parse signed decimal degrees leniently (sign optional, 1-2 integer digits, any decimals)."""
    if _DEC_PATTERN.fullmatch(text) is None:
        raise CoordinateRangeError(f"Dec is not decimal degrees: {text!r}")
    value = float(text)
    return check_dec_degrees(value) + 0.0  # normalises -0.0


def ra_sexagesimal(ra_hours: float) -> str:
    """``"12h 20m 42s"``, to the nearest second."""
    total = round(ra_hours * 3600.0) % (24 * 3600)
    return f"{total // 3600:02d}h {total // 60 % 60:02d}m {total % 60:02d}s"


def dec_text(dec_degrees: float) -> str:
    """``"+67.890°"``."""
    return f"{dec_degrees:+.{_DECIMALS}f}°"
