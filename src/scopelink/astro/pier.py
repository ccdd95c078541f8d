"""Hour angle, German-equatorial pier side, and angular separation.

Pier side follows ASCOM's ``PierSide`` values and INDI's convention: a target west of the
meridian (hour angle > 0) is observed with the tube on the east side of the
pier looking west (``EAST``, ASCOM's normal pointing state), a target east of the meridian or on
it with the tube on the west side looking east (``WEST``).
"""

from __future__ import annotations

import enum
from typing import overload

import numpy as np
import numpy.typing as npt

from scopelink.astro._arrays import FloatOrArray, as_float_array, scalar_or_array
from scopelink.astro.angles import wrap_hour_angle

__all__ = ["PierSide", "angular_separation_deg", "destination_side_of_pier", "hour_angle_hours"]


class PierSide(enum.IntEnum):
    """Side of the pier the tube is on (values as ASCOM's ``PierSide``)."""

    UNKNOWN = -1
    EAST = 0
    WEST = 1


@overload
def hour_angle_hours(lst_hours: float, ra_hours: float) -> float: ...
@overload
def hour_angle_hours(lst_hours: npt.ArrayLike, ra_hours: npt.ArrayLike) -> FloatOrArray: ...
def hour_angle_hours(lst_hours: npt.ArrayLike, ra_hours: npt.ArrayLike) -> FloatOrArray:
    """Local hour angle LST - RA in hours, wrapped to [-12, 12) (positive west of meridian).

    Use apparent sidereal time with apparent (of-date) RA.
    """
    return wrap_hour_angle(as_float_array(lst_hours) - as_float_array(ra_hours))


def destination_side_of_pier(ha_hours: float) -> PierSide:
    """Where a German equatorial mount's tube ends up for a target at hour angle ``ha_hours``.

    ``EAST`` for targets west of the meridian (0 < HA < 12 after wrapping), ``WEST`` for
    targets east of it or exactly on it. The same in both hemispheres: the tube sits on the side
    of the pier opposite the half of the sky it looks at.
    """
    if not np.isfinite(ha_hours):
        return PierSide.UNKNOWN
    return PierSide.EAST if wrap_hour_angle(float(ha_hours)) > 0.0 else PierSide.WEST


@overload
def angular_separation_deg(
    lon1_deg: float, lat1_deg: float, lon2_deg: float, lat2_deg: float
) -> float: ...
@overload
def angular_separation_deg(
    lon1_deg: npt.ArrayLike,
    lat1_deg: npt.ArrayLike,
    lon2_deg: npt.ArrayLike,
    lat2_deg: npt.ArrayLike,
) -> FloatOrArray: ...
def angular_separation_deg(
    lon1_deg: npt.ArrayLike,
    lat1_deg: npt.ArrayLike,
    lon2_deg: npt.ArrayLike,
    lat2_deg: npt.ArrayLike,
) -> FloatOrArray:
    """Great-circle separation in degrees between two (longitude, latitude) directions.

    Works for (az, alt) and, with RA multiplied by 15, for (RA, Dec). Uses Vincenty's formula,
    accurate at every separation from 0 to 180 degrees.
    """
    lon1, lat1, lon2, lat2 = (
        np.radians(as_float_array(value)) for value in (lon1_deg, lat1_deg, lon2_deg, lat2_deg)
    )
    delta = lon2 - lon1
    sin_lat1, cos_lat1 = np.sin(lat1), np.cos(lat1)
    sin_lat2, cos_lat2 = np.sin(lat2), np.cos(lat2)
    across = cos_lat2 * np.sin(delta)
    along = cos_lat1 * sin_lat2 - sin_lat1 * cos_lat2 * np.cos(delta)
    towards = sin_lat1 * sin_lat2 + cos_lat1 * cos_lat2 * np.cos(delta)
    return scalar_or_array(np.degrees(np.arctan2(np.hypot(across, along), towards)))
