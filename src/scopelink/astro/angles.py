"""Angle wrapping and sexagesimal text: "4h 57m 12.3s", "+26°26'39\"", "12:34:56", "-05 30 00"."""

from __future__ import annotations

import math
import re
from typing import Literal, overload

import numpy as np
import numpy.typing as npt

from scopelink.astro._arrays import FloatOrArray, as_float_array, scalar_or_array

__all__ = [
    "SexagesimalStyle",
    "format_degrees",
    "format_hours",
    "parse_degrees",
    "parse_hours",
    "wrap_degrees",
    "wrap_hour_angle",
    "wrap_hours",
    "wrap_signed_degrees",
]

SexagesimalStyle = Literal["units", "colons", "spaces"]


def _wrap(value: npt.ArrayLike, period: float, low: float) -> FloatOrArray:
    one: object = value
    if isinstance(one, float):  # np.float64 too
        # One value (a poll's): Python's float modulo is np.mod's arithmetic, a tenth the cost.
        folded = (float(one) - low) % period
        return (0.0 if folded >= period else folded) + low
    shifted = np.mod(as_float_array(value) - low, period)
    # np.mod can return exactly `period` for tiny negative inputs; fold it back into range.
    shifted = np.where(shifted >= period, 0.0, shifted)
    return scalar_or_array(shifted + low)


@overload
def wrap_hours(hours: float) -> float: ...
@overload
def wrap_hours(hours: npt.ArrayLike) -> FloatOrArray: ...
def wrap_hours(hours: npt.ArrayLike) -> FloatOrArray:
    """Wrap hours (RA, sidereal time) into [0, 24)."""
    return _wrap(hours, 24.0, 0.0)


@overload
def wrap_hour_angle(hours: float) -> float: ...
@overload
def wrap_hour_angle(hours: npt.ArrayLike) -> FloatOrArray: ...
def wrap_hour_angle(hours: npt.ArrayLike) -> FloatOrArray:
    """Wrap an hour angle into [-12, 12): negative east of the meridian, positive west."""
    return _wrap(hours, 24.0, -12.0)


@overload
def wrap_degrees(degrees: float) -> float: ...
@overload
def wrap_degrees(degrees: npt.ArrayLike) -> FloatOrArray: ...
def wrap_degrees(degrees: npt.ArrayLike) -> FloatOrArray:
    """Wrap degrees (azimuth, longitude) into [0, 360)."""
    return _wrap(degrees, 360.0, 0.0)


@overload
def wrap_signed_degrees(degrees: float) -> float: ...
@overload
def wrap_signed_degrees(degrees: npt.ArrayLike) -> FloatOrArray: ...
def wrap_signed_degrees(degrees: npt.ArrayLike) -> FloatOrArray:
    """Wrap degrees into [-180, 180)."""
    return _wrap(degrees, 360.0, -180.0)


# --- formatting ---------------------------------------------------------------------------------

_UNIT_MARKS: dict[SexagesimalStyle, tuple[tuple[str, str, str], tuple[str, str, str]]] = {
    # (hours marks, degrees marks): text after the big unit, the minutes and the seconds.
    "units": (("h ", "m ", "s"), ("°", "'", '"')),
    "colons": ((":", ":", ""), (":", ":", "")),
    "spaces": ((" ", " ", ""), (" ", " ", "")),
}


def _split(value: float, decimals: int) -> tuple[bool, int, int, str]:
    """Sign, whole units, minutes and seconds text, rounded once so 59.96 s carries over."""
    if not math.isfinite(value):
        raise ValueError(f"cannot format a non-finite angle: {value!r}")
    if not 0 <= decimals <= 9:
        raise ValueError(f"decimals must be between 0 and 9, got {decimals}")
    scale = 10**decimals
    ticks = round(abs(value) * 3600 * scale)
    negative = value < 0 and ticks != 0
    seconds_ticks = ticks % (60 * scale)
    minutes_total = ticks // (60 * scale)
    whole, minutes = divmod(minutes_total, 60)
    width = 2 + (decimals + 1 if decimals else 0)
    seconds = f"{seconds_ticks / scale:0{width}.{decimals}f}"
    return negative, whole, minutes, seconds


def format_hours(
    hours: float, *, decimals: int = 1, style: SexagesimalStyle = "units", signed: bool = False
) -> str:
    """Format hours as "4h 57m 12.3s" ("04:57:12.3" with ``style="colons"``).

    Unsigned values (RA, sidereal time) are wrapped into [0, 24) after rounding, so 23:59:59.96
    shows as 00:00:00.0. ``signed=True`` keeps the sign for hour angles and offsets ("-1h ...").
    """
    value = float(hours) if signed else wrap_hours(float(hours))
    negative, whole, minutes, seconds = _split(value, decimals)
    if not signed:
        whole %= 24
    big, minute_mark, second_mark = _UNIT_MARKS[style][0]
    digits = f"{whole}" if style == "units" else f"{whole:02d}"
    sign = ("-" if negative else "+") if signed else ""
    return f"{sign}{digits}{big}{minutes:02d}{minute_mark}{seconds}{second_mark}"


def format_degrees(
    degrees: float, *, decimals: int = 0, style: SexagesimalStyle = "units", width: int = 2
) -> str:
    """Format signed degrees as "+26°26'39\"" ("+26:26:39" with ``style="colons"``).

    ``width`` is the zero-padded width of the degrees field (3 suits azimuth and longitude).
    """
    negative, whole, minutes, seconds = _split(float(degrees), decimals)
    big, minute_mark, second_mark = _UNIT_MARKS[style][1]
    sign = "-" if negative else "+"
    return f"{sign}{whole:0{width}d}{big}{minutes:02d}{minute_mark}{seconds}{second_mark}"


# --- parsing ------------------------------------------------------------------------------------

_NUMBER = r"(\d+(?:\.\d*)?|\.\d+)"
_BIG_MARK = r"(?:[hHdD°º:]|\s)"
_MINUTE_MARK = r"(?:[mM'′’:]|\s)"
_SECOND_MARK = r"[sS\"″”]|''|′′"
_SEXAGESIMAL = re.compile(
    rf"""^\s*(?P<sign>[-+−])?\s*
    (?P<big>{_NUMBER})\s*
    (?:{_BIG_MARK}\s*(?P<minutes>{_NUMBER})?\s*
       (?:{_MINUTE_MARK}\s*(?P<seconds>{_NUMBER})?\s*(?:{_SECOND_MARK})?\s*)?
    )?$""",
    re.VERBOSE,
)


def _parse(text: str, what: str) -> float:
    match = _SEXAGESIMAL.match(text)
    if match is None:
        raise ValueError(
            f"cannot read {what} from {text!r}: expected e.g. '12:34:56.7', '12 34 56', "
            "'12h34m56s', \"+26°26'39\\\"\", '-05 30 00' or a decimal number"
        )
    parts = [match["big"], match["minutes"], match["seconds"]]
    present = [part for part in parts if part is not None]
    if any("." in part for part in present[:-1]):
        raise ValueError(f"only the last field may have decimals in {what} {text!r}")
    big, minutes, seconds = (float(part) if part is not None else 0.0 for part in parts)
    if minutes >= 60 or seconds >= 60:
        raise ValueError(f"minutes and seconds must be below 60 in {what} {text!r}")
    value = big + minutes / 60 + seconds / 3600
    if not math.isfinite(value):
        raise ValueError(f"{what} {text!r} is too large")
    return -value if match["sign"] in ("-", "−") else value


def parse_hours(text: str) -> float:
    """Read hours from "12:34:56", "12 34 56.7", "4h 57m 12.3s", "12:34.5" or "12.582".

    A leading sign is kept (hour angles), so "-0:30:00" is -0.5.
    """
    return _parse(text, "hours")


def parse_degrees(text: str) -> float:
    """Read degrees from "+26°26'39\"", "-05 30 00", "26d26m39s", "-0:30", "26:26.6" or "26.44".

    A sign applies to the whole value, so "-00 30 00" is -0.5.
    """
    return _parse(text, "degrees")
