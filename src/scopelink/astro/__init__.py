"""Astronomy core on ERFA: time scales, sidereal time, frames, refraction.

Pure functions over plain floats: hours for RA, hour angle and sidereal time; degrees for Dec,
altitude, azimuth (North = 0, East = 90), latitude and longitude (east positive). Every function
takes floats or numpy arrays (broadcast together) and returns floats for scalar inputs, arrays
otherwise. See ``docs/astronomy.md``.
"""

from scopelink.astro.angles import (
    format_degrees,
    format_hours,
    parse_degrees,
    parse_hours,
    wrap_degrees,
    wrap_hour_angle,
    wrap_hours,
    wrap_signed_degrees,
)
from scopelink.astro.frames import (
    apparent_to_j2000,
    j2000_to_apparent,
    j2000_to_mean_of_date,
    mean_of_date_to_j2000,
)
from scopelink.astro.horizontal import (
    altaz_to_hadec,
    apparent_to_observed,
    hadec_to_altaz,
    j2000_to_observed,
    observed_to_apparent,
    observed_to_j2000,
)
from scopelink.astro.pier import (
    PierSide,
    angular_separation_deg,
    destination_side_of_pier,
    hour_angle_hours,
)
from scopelink.astro.rates import (
    KING_RATE_DEG_S,
    LUNAR_RATE_DEG_S,
    SIDEREAL_DAY_S,
    SIDEREAL_RATE_DEG_S,
    SOLAR_RATE_DEG_S,
)
from scopelink.astro.refraction import (
    RefractionModel,
    observed_altitude_deg,
    refraction_deg,
    true_altitude_deg,
)
from scopelink.astro.sidereal import gast_hours, gmst_hours, lst_hours
from scopelink.astro.site import Site
from scopelink.astro.timescales import (
    JulianDate,
    TimeLike,
    now,
    tai_jd,
    tai_minus_utc_s,
    tt_jd,
    ut1_jd,
    utc_jd,
)

__all__ = [
    "KING_RATE_DEG_S",
    "LUNAR_RATE_DEG_S",
    "SIDEREAL_DAY_S",
    "SIDEREAL_RATE_DEG_S",
    "SOLAR_RATE_DEG_S",
    "JulianDate",
    "PierSide",
    "RefractionModel",
    "Site",
    "TimeLike",
    "altaz_to_hadec",
    "angular_separation_deg",
    "apparent_to_j2000",
    "apparent_to_observed",
    "destination_side_of_pier",
    "format_degrees",
    "format_hours",
    "gast_hours",
    "gmst_hours",
    "hadec_to_altaz",
    "hour_angle_hours",
    "j2000_to_apparent",
    "j2000_to_mean_of_date",
    "j2000_to_observed",
    "lst_hours",
    "mean_of_date_to_j2000",
    "now",
    "observed_altitude_deg",
    "observed_to_apparent",
    "observed_to_j2000",
    "parse_degrees",
    "parse_hours",
    "refraction_deg",
    "tai_jd",
    "tai_minus_utc_s",
    "true_altitude_deg",
    "tt_jd",
    "ut1_jd",
    "utc_jd",
    "wrap_degrees",
    "wrap_hour_angle",
    "wrap_hours",
    "wrap_signed_degrees",
]
