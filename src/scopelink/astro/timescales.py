"""Time scales: UTC, TAI, TT and UT1 as two-part Julian dates, with leap seconds from ERFA.

Every function takes a *time-like* value:

- a timezone-aware :class:`datetime.datetime` (naive ones are refused: their zone is a guess);
- a ``(jd1, jd2)`` pair of floats or arrays, read as a UTC quasi Julian date in ERFA's
  convention (the sum is the date; leap-second days are handled by ERFA);
- anything with ``jd1``, ``jd2`` and ``scale`` attributes, such as :class:`JulianDate` or an
  ``astropy.time.Time`` (scales ``utc``, ``tai`` and ``tt`` are converted here, any other scale
  through the object's own ``utc`` attribute), without importing astropy;
- anything with a ``to_datetime()`` method returning an aware ``datetime``.

UT1 is UTC plus a caller-supplied ``ut1_minus_utc_s`` (DUT1, published by the IERS, always within
±0.9 s). Leaving it at 0 puts sidereal time and every hour angle and azimuth off by up to 0.9 s of
time, i.e. up to 13.5 arcseconds of rotation about the pole.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, Protocol, TypeAlias, overload, runtime_checkable

import erfa
import numpy as np
import numpy.typing as npt

from scopelink.astro._arrays import FloatArray, FloatOrArray, as_float_array, scalar_or_array

__all__ = [
    "MAX_ABS_UT1_MINUS_UTC_S",
    "JulianDate",
    "ScalarTime",
    "SupportsJulianDate",
    "SupportsToDatetime",
    "TimeLike",
    "now",
    "tai_jd",
    "tai_minus_utc_s",
    "tt_jd",
    "ut1_jd",
    "utc_day_seconds",
    "utc_jd",
]

MAX_ABS_UT1_MINUS_UTC_S = 0.9
"""The IERS keeps |UT1 - UTC| below this by inserting leap seconds."""

_SECONDS_PER_DAY = 86400.0


@runtime_checkable
class SupportsJulianDate(Protocol):
    """A two-part Julian date with a named time scale (``astropy.time.Time`` qualifies)."""

    @property
    def jd1(self) -> Any: ...

    @property
    def jd2(self) -> Any: ...

    @property
    def scale(self) -> str: ...


@runtime_checkable
class SupportsToDatetime(Protocol):
    """Anything that can give a :class:`datetime.datetime`."""

    def to_datetime(self) -> Any: ...


@dataclass(frozen=True, slots=True)
class JulianDate:
    """A two-part Julian date ``jd1 + jd2`` in the time scale ``scale`` (utc, tai or tt)."""

    jd1: FloatOrArray
    jd2: FloatOrArray
    scale: str = "utc"

    def __post_init__(self) -> None:
        if self.scale not in _SCALES_HANDLED_HERE:
            raise ValueError(
                f"JulianDate scale must be one of {sorted(_SCALES_HANDLED_HERE)}, "
                f"not {self.scale!r}"
            )


ScalarTime: TypeAlias = datetime | tuple[float, float]
"""Time-like values that always denote a single instant."""

TimeLike: TypeAlias = (
    datetime
    | tuple[npt.ArrayLike, npt.ArrayLike]
    | JulianDate
    | SupportsJulianDate
    | SupportsToDatetime
)

_SCALES_HANDLED_HERE = frozenset({"utc", "tai", "tt"})


def now() -> datetime:
    """The current time as an aware UTC datetime: the only clock in this package."""
    return datetime.now(UTC)


def utc_pair(t: TimeLike) -> tuple[FloatArray, FloatArray]:
    """UTC two-part quasi Julian date of ``t`` as float arrays (0-d for one instant)."""
    if isinstance(t, datetime):
        return _utc_pair_from_datetime(t)
    if isinstance(t, tuple):
        if len(t) != 2:
            raise TypeError(f"a Julian date tuple must be (jd1, jd2), got {len(t)} items")
        jd1, jd2 = np.broadcast_arrays(as_float_array(t[0]), as_float_array(t[1]))
        return jd1, jd2
    if isinstance(t, SupportsJulianDate):
        return _utc_pair_from_julian_date(t)
    if isinstance(t, SupportsToDatetime):
        converted = t.to_datetime()
        if not isinstance(converted, datetime):
            raise TypeError(
                f"{type(t).__name__}.to_datetime() returned {type(converted).__name__}, "
                "expected one datetime; pass arrays of instants as a (jd1, jd2) pair"
            )
        return _utc_pair_from_datetime(converted)
    raise TypeError(
        f"cannot read a time from {type(t).__name__}: pass an aware datetime, a UTC (jd1, jd2) "
        "pair, an object with jd1/jd2/scale (e.g. astropy Time) or one with to_datetime()"
    )


def _utc_pair_from_datetime(moment: datetime) -> tuple[FloatArray, FloatArray]:
    day_jd, seconds, day_seconds = utc_day_seconds(moment)
    return np.asarray(day_jd), np.asarray(seconds / day_seconds)


def utc_day_seconds(moment: datetime) -> tuple[float, float, float]:
    """(Julian date of the UTC day's 0h, UTC seconds since then, the day's length in SI seconds)
    of an aware datetime: ``seconds / length`` is the day fraction of :func:`utc_jd` (ERFA's
    quasi Julian date), and within one UTC day UT1 = JD(0h) + (seconds + DUT1) / 86400 exactly
    (``erfa.utcut1``, leap-second days included)."""
    global _last_day_seconds  # noqa: PLW0603 - a one-entry cache: one reading, two conversions
    last = _last_day_seconds
    if last is not None and last[0] is moment:  # a datetime is immutable: the same object
        return last[1]
    if moment.tzinfo is UTC:  # a mount's clock (utc_now, SimClock): no offset to ask for
        utc = moment
    else:
        offset = moment.utcoffset()
        if offset is None:
            raise ValueError(
                f"naive datetime {moment.isoformat()} has no time zone; attach one, "
                "e.g. datetime(..., tzinfo=timezone.utc) or "
                "moment.replace(tzinfo=zoneinfo.ZoneInfo(...))"
            )
        utc = moment.astimezone(UTC) if offset else moment  # a zero offset: UTC's fields
    day_jd, day_seconds = _utc_day(utc.year, utc.month, utc.day)
    seconds = seconds_of_utc_day(utc)
    _last_day_seconds = (moment, (day_jd, seconds, day_seconds))
    return day_jd, seconds, day_seconds


_last_day_seconds: tuple[datetime, tuple[float, float, float]] | None = None


def seconds_of_utc_day(utc: datetime) -> float:
    """UTC seconds since 0h of ``utc``'s day (a UTC datetime), as :func:`utc_day_seconds` gives
    them: ``erfa.dtf2d``'s own expression, term for term (the same doubles), so a poll's
    datetime costs a cached day and one division instead of three ufunc calls."""
    return 60.0 * float(60 * utc.hour + utc.minute) + (utc.second + utc.microsecond * 1e-6)


@functools.lru_cache(maxsize=16)
def _utc_day(year: int, month: int, day: int) -> tuple[float, float]:
    """(Julian date of 0h, length in SI seconds) of a UTC day, as ``erfa.dtf2d`` finds them
    (86401 s on a day ending with a leap second)."""
    day_jd, _ = erfa.dtf2d("UTC", year, month, day, 0, 0, 0.0)
    at_0h = erfa.dat(year, month, day, 0.0)
    at_12h = erfa.dat(year, month, day, 0.5)
    next_year, next_month, next_day, _ = erfa.jd2cal(day_jd, 1.5)
    next_0h = erfa.dat(next_year, next_month, next_day, 0.0)
    return float(day_jd), _SECONDS_PER_DAY + float(next_0h - (2.0 * at_12h - at_0h))


def _utc_pair_from_julian_date(t: SupportsJulianDate) -> tuple[FloatArray, FloatArray]:
    scale = str(t.scale).lower()
    jd1, jd2 = np.broadcast_arrays(as_float_array(t.jd1), as_float_array(t.jd2))
    if scale == "utc":
        return jd1, jd2
    if scale == "tt":
        jd1, jd2 = erfa.tttai(jd1, jd2)
        scale = "tai"
    if scale == "tai":
        utc1, utc2 = erfa.taiutc(jd1, jd2)
        return as_float_array(utc1), as_float_array(utc2)
    in_utc = getattr(t, "utc", None)
    if isinstance(in_utc, SupportsJulianDate) and str(in_utc.scale).lower() == "utc":
        return _utc_pair_from_julian_date(in_utc)
    raise ValueError(
        f"time scale {t.scale!r} is not handled here and the object has no 'utc' view; "
        "convert it to utc, tai or tt first"
    )


def check_ut1_minus_utc(ut1_minus_utc_s: float) -> None:
    """Refuse a DUT1 outside ±0.9 s: it is surely in the wrong unit or sign convention."""
    if not abs(ut1_minus_utc_s) <= MAX_ABS_UT1_MINUS_UTC_S:
        raise ValueError(
            f"UT1-UTC must be within ±{MAX_ABS_UT1_MINUS_UTC_S} s (IERS bulletin A value), "
            f"got {ut1_minus_utc_s!r}"
        )


def _atomic_pair(t: TimeLike) -> tuple[str, FloatArray, FloatArray] | None:
    """(scale, jd1, jd2) when ``t`` is already in TAI or TT: no leap-second table needed."""
    if isinstance(t, tuple | datetime):
        return None  # before the Protocol check, which costs 25 us per call
    if isinstance(t, SupportsJulianDate):
        scale = str(t.scale).lower()
        if scale in ("tai", "tt"):
            jd1, jd2 = np.broadcast_arrays(as_float_array(t.jd1), as_float_array(t.jd2))
            return scale, jd1, jd2
    return None


def tai_pair(t: TimeLike) -> tuple[FloatArray, FloatArray]:
    """TAI two-part Julian date of ``t`` as float arrays."""
    atomic = _atomic_pair(t)
    if atomic is None:
        tai1, tai2 = erfa.utctai(*utc_pair(t))
    else:
        scale, jd1, jd2 = atomic
        tai1, tai2 = erfa.tttai(jd1, jd2) if scale == "tt" else (jd1, jd2)
    return as_float_array(tai1), as_float_array(tai2)


def tt_pair(t: TimeLike) -> tuple[FloatArray, FloatArray]:
    """TT two-part Julian date of ``t`` as float arrays."""
    atomic = _atomic_pair(t)
    if atomic is not None and atomic[0] == "tt":
        return atomic[1], atomic[2]
    tt1, tt2 = erfa.taitt(*tai_pair(t))
    return as_float_array(tt1), as_float_array(tt2)


def ut1_pair(t: TimeLike, ut1_minus_utc_s: float = 0.0) -> tuple[FloatArray, FloatArray]:
    """UT1 two-part Julian date of ``t`` as float arrays, given DUT1 = UT1 - UTC in seconds."""
    check_ut1_minus_utc(ut1_minus_utc_s)
    ut11, ut12 = erfa.utcut1(*utc_pair(t), ut1_minus_utc_s)
    return as_float_array(ut11), as_float_array(ut12)


def _public(pair: tuple[FloatArray, FloatArray]) -> tuple[FloatOrArray, FloatOrArray]:
    return scalar_or_array(pair[0]), scalar_or_array(pair[1])


@overload
def utc_jd(t: ScalarTime) -> tuple[float, float]: ...
@overload
def utc_jd(t: TimeLike) -> tuple[FloatOrArray, FloatOrArray]: ...
def utc_jd(t: TimeLike) -> tuple[FloatOrArray, FloatOrArray]:
    """UTC two-part quasi Julian date (ERFA convention) of ``t``."""
    return _public(utc_pair(t))


@overload
def tai_jd(t: ScalarTime) -> tuple[float, float]: ...
@overload
def tai_jd(t: TimeLike) -> tuple[FloatOrArray, FloatOrArray]: ...
def tai_jd(t: TimeLike) -> tuple[FloatOrArray, FloatOrArray]:
    """TAI two-part Julian date of ``t``."""
    return _public(tai_pair(t))


@overload
def tt_jd(t: ScalarTime) -> tuple[float, float]: ...
@overload
def tt_jd(t: TimeLike) -> tuple[FloatOrArray, FloatOrArray]: ...
def tt_jd(t: TimeLike) -> tuple[FloatOrArray, FloatOrArray]:
    """TT two-part Julian date of ``t`` (TT = TAI + 32.184 s)."""
    return _public(tt_pair(t))


@overload
def ut1_jd(t: ScalarTime, ut1_minus_utc_s: float = 0.0) -> tuple[float, float]: ...
@overload
def ut1_jd(t: TimeLike, ut1_minus_utc_s: float = 0.0) -> tuple[FloatOrArray, FloatOrArray]: ...
def ut1_jd(t: TimeLike, ut1_minus_utc_s: float = 0.0) -> tuple[FloatOrArray, FloatOrArray]:
    """UT1 two-part Julian date of ``t``, given DUT1 = UT1 - UTC in seconds (|DUT1| <= 0.9)."""
    return _public(ut1_pair(t, ut1_minus_utc_s))


def tai_minus_utc_s(t: TimeLike) -> FloatOrArray:
    """TAI - UTC in seconds at ``t`` (37 s since 2017), from ERFA's leap-second table."""
    year, month, day, fraction = erfa.jd2cal(*utc_pair(t))
    return scalar_or_array(erfa.dat(year, month, day, fraction))
