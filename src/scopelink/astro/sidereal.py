"""Sidereal time (IAU 2006/2000A) in hours, Greenwich and local."""

from __future__ import annotations

from typing import overload

import erfa
import numpy as np
import numpy.typing as npt

from scopelink.astro._arrays import FloatArray, FloatOrArray, as_float_array, scalar_or_array
from scopelink.astro.timescales import ScalarTime, TimeLike, tt_pair, ut1_pair

__all__ = ["gast_hours", "gmst_hours", "lst_hours"]

_HOURS_PER_RADIAN = 12.0 / np.pi


def greenwich_sidereal_radians(
    t: TimeLike, *, apparent: bool, ut1_minus_utc_s: float = 0.0
) -> FloatArray:
    """Greenwich sidereal time in radians [0, 2π): apparent (GAST) or mean (GMST)."""
    ut1 = ut1_pair(t, ut1_minus_utc_s)
    tt = tt_pair(t)
    angle = erfa.gst06a(*ut1, *tt) if apparent else erfa.gmst06(*ut1, *tt)
    return as_float_array(angle)


def _to_hours(radians: npt.ArrayLike) -> FloatArray:
    hours = np.mod(as_float_array(radians) * _HOURS_PER_RADIAN, 24.0)
    return np.where(hours >= 24.0, 0.0, hours)


@overload
def gmst_hours(t: ScalarTime, *, ut1_minus_utc_s: float = 0.0) -> float: ...
@overload
def gmst_hours(t: TimeLike, *, ut1_minus_utc_s: float = 0.0) -> FloatOrArray: ...
def gmst_hours(t: TimeLike, *, ut1_minus_utc_s: float = 0.0) -> FloatOrArray:
    """Greenwich mean sidereal time (IAU 2006, ``erfa.gmst06``) in hours [0, 24)."""
    angle = greenwich_sidereal_radians(t, apparent=False, ut1_minus_utc_s=ut1_minus_utc_s)
    return scalar_or_array(_to_hours(angle))


@overload
def gast_hours(t: ScalarTime, *, ut1_minus_utc_s: float = 0.0) -> float: ...
@overload
def gast_hours(t: TimeLike, *, ut1_minus_utc_s: float = 0.0) -> FloatOrArray: ...
def gast_hours(t: TimeLike, *, ut1_minus_utc_s: float = 0.0) -> FloatOrArray:
    """Greenwich apparent sidereal time (IAU 2006/2000A, ``erfa.gst06a``) in hours [0, 24)."""
    angle = greenwich_sidereal_radians(t, apparent=True, ut1_minus_utc_s=ut1_minus_utc_s)
    return scalar_or_array(_to_hours(angle))


@overload
def lst_hours(
    t: ScalarTime,
    longitude_deg: float,
    *,
    apparent: bool = True,
    ut1_minus_utc_s: float = 0.0,
) -> float: ...
@overload
def lst_hours(
    t: TimeLike,
    longitude_deg: npt.ArrayLike,
    *,
    apparent: bool = True,
    ut1_minus_utc_s: float = 0.0,
) -> FloatOrArray: ...
def lst_hours(
    t: TimeLike,
    longitude_deg: npt.ArrayLike,
    *,
    apparent: bool = True,
    ut1_minus_utc_s: float = 0.0,
) -> FloatOrArray:
    """Local sidereal time in hours [0, 24) at east-positive ``longitude_deg``.

    Apparent (from GAST) by default, which is what hour angles of apparent places need;
    ``apparent=False`` gives local mean sidereal time. Polar motion is neglected (< 0.1 s).
    """
    greenwich = greenwich_sidereal_radians(t, apparent=apparent, ut1_minus_utc_s=ut1_minus_utc_s)
    return scalar_or_array(_to_hours(greenwich + np.radians(as_float_array(longitude_deg))))
