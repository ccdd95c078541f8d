"""J2000 (ICRS) <-> of-date equatorial coordinates.

*Apparent of date* is the position on the true equator and equinox of date as seen from the
geocentre: IAU 2006/2000A precession-nutation, annual aberration and light deflection by the Sun,
no proper motion or parallax (the catalogue position is taken at the date). This is "JNow" for
LX200-style clients. ERFA works in CIRS (RA from the celestial intermediate origin); the
equinox-based RA is RA_CIRS - EO, with EO the equation of the origins (``erfa.eo06a``).

*Mean of date* is the mean equator and equinox of date (frame bias and IAU 2006 precession
only, no nutation and no aberration): what a precession-only client means by "of date".
"""

from __future__ import annotations

import math
from datetime import datetime
from typing import Any, overload

import erfa
import numpy as np
import numpy.typing as npt

from scopelink.astro._arrays import FloatArray, FloatOrArray, as_float_array, scalar_or_array
from scopelink.astro.one_position import GEOCENTRIC_REUSE_S, apparent_of_j2000
from scopelink.astro.timescales import ScalarTime, TimeLike, tt_pair, utc_pair

__all__ = [
    "apparent_to_j2000",
    "j2000_to_apparent",
    "j2000_to_mean_of_date",
    "mean_of_date_to_j2000",
]

_RADIANS_PER_HOUR = np.pi / 12.0


def radec_radians(ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """RA hours and Dec degrees as radians."""
    return as_float_array(ra_hours) * _RADIANS_PER_HOUR, np.radians(as_float_array(dec_deg))


def radec_public(
    ra_rad: npt.ArrayLike, dec_rad: npt.ArrayLike
) -> tuple[FloatOrArray, FloatOrArray]:
    """Radians as (RA hours in [0, 24), Dec degrees), floats for single positions."""
    ra: object = ra_rad
    dec: object = dec_rad
    if isinstance(ra, float) and isinstance(dec, float):  # np.float64 too
        # np.mod's and np.degrees' arithmetic in Python floats (the same doubles).
        one = (float(ra) / _RADIANS_PER_HOUR) % 24.0
        return (0.0 if one >= 24.0 else one), math.degrees(float(dec))
    hours = np.mod(as_float_array(ra_rad) / _RADIANS_PER_HOUR, 24.0)
    hours = np.where(hours >= 24.0, 0.0, hours)
    return scalar_or_array(hours), scalar_or_array(np.degrees(as_float_array(dec_rad)))


_REUSE_WITHIN_DAYS = GEOCENTRIC_REUSE_S / 86400.0

_last_geocentric: tuple[tuple[bool, float], Any, FloatArray] | None = None


def _geocentric(t: TimeLike) -> tuple[Any, FloatArray]:
    """``erfa.apci13`` at ``t``, reused for one instant within 1 s of the previous one."""
    global _last_geocentric  # noqa: PLW0603 - a one-entry cache of the most recent instant
    # The cache's key: a datetime's UTC (cheap: its TT costs 20 us), anything else's TT.
    jd1, jd2 = utc_pair(t) if isinstance(t, datetime) else tt_pair(t)
    if np.ndim(jd1) != 0:
        astrom, equation_of_origins = erfa.apci13(*tt_pair(t))
        return astrom, as_float_array(equation_of_origins)
    key = (isinstance(t, datetime), float(jd1) + float(jd2))
    cached = _last_geocentric
    if (
        cached is not None
        and cached[0][0] == key[0]
        and abs(key[1] - cached[0][1]) <= _REUSE_WITHIN_DAYS
    ):
        return cached[1], cached[2]
    astrom, equation_of_origins = erfa.apci13(*tt_pair(t))
    _last_geocentric = (key, astrom, as_float_array(equation_of_origins))
    return astrom, _last_geocentric[2]


@overload
def j2000_to_apparent(ra_hours: float, dec_deg: float, t: ScalarTime) -> tuple[float, float]: ...
@overload
def j2000_to_apparent(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]: ...
def j2000_to_apparent(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]:
    """J2000 (ICRS) RA/Dec -> apparent RA/Dec of date (true equator and equinox)."""
    ra_one: object = ra_hours
    dec_one: object = dec_deg
    if isinstance(ra_one, float) and isinstance(dec_one, float) and isinstance(t, datetime):
        return apparent_of_j2000(ra_one, dec_one, t)  # a poll's: one position, in floats
    astrom, equation_of_origins = _geocentric(t)
    ra, dec = radec_radians(ra_hours, dec_deg)
    cirs_ra, cirs_dec = erfa.atciqz(ra, dec, astrom)
    return radec_public(cirs_ra - equation_of_origins, cirs_dec)


@overload
def apparent_to_j2000(ra_hours: float, dec_deg: float, t: ScalarTime) -> tuple[float, float]: ...
@overload
def apparent_to_j2000(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]: ...
def apparent_to_j2000(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]:
    """Apparent RA/Dec of date (true equator and equinox) -> J2000 (ICRS) RA/Dec."""
    astrom, equation_of_origins = _geocentric(t)
    ra, dec = radec_radians(ra_hours, dec_deg)
    icrs_ra, icrs_dec = erfa.aticq(ra + equation_of_origins, dec, astrom)
    return radec_public(icrs_ra, icrs_dec)


def _rotate(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike, *, inverse: bool
) -> tuple[FloatOrArray, FloatOrArray]:
    bias_precession = erfa.pmat06(*tt_pair(t))
    vector = erfa.s2c(*radec_radians(ra_hours, dec_deg))
    rotated = erfa.trxp(bias_precession, vector) if inverse else erfa.rxp(bias_precession, vector)
    return radec_public(*erfa.c2s(rotated))


@overload
def j2000_to_mean_of_date(
    ra_hours: float, dec_deg: float, t: ScalarTime
) -> tuple[float, float]: ...
@overload
def j2000_to_mean_of_date(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]: ...
def j2000_to_mean_of_date(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]:
    """J2000 (ICRS) RA/Dec -> mean RA/Dec of date (bias + precession, no nutation/aberration)."""
    return _rotate(ra_hours, dec_deg, t, inverse=False)


@overload
def mean_of_date_to_j2000(
    ra_hours: float, dec_deg: float, t: ScalarTime
) -> tuple[float, float]: ...
@overload
def mean_of_date_to_j2000(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]: ...
def mean_of_date_to_j2000(
    ra_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, t: TimeLike
) -> tuple[FloatOrArray, FloatOrArray]:
    """Mean RA/Dec of date -> J2000 (ICRS) RA/Dec: the exact inverse rotation."""
    return _rotate(ra_hours, dec_deg, t, inverse=True)
