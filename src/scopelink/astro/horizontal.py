"""Equatorial <-> horizontal coordinates for a :class:`~scopelink.astro.site.Site`.

Azimuth is in degrees [0, 360), North = 0, East = 90 (ERFA's convention); altitude in degrees.
*Observed* alt/az include atmospheric refraction for the site's air (none when its pressure is
0); they are what a level alt-az mount points at. ERFA carries the geometry (precession-nutation,
aberration, light deflection, Earth rotation, diurnal aberration, parallax-free topocentric
direction) with its own refraction switched off; :mod:`scopelink.astro.refraction` then adds
refraction to the altitude (``refract``) or removes it (``unrefract``). Polar motion is neglected
(below 0.5 arcsec).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime
from typing import Any, overload

import erfa
import numpy as np
import numpy.typing as npt

from scopelink.astro._arrays import FloatArray, FloatOrArray, as_float_array, scalar_or_array
from scopelink.astro.angles import wrap_degrees, wrap_hour_angle
from scopelink.astro.frames import radec_public, radec_radians
from scopelink.astro.one_position import OBSERVER_REUSE_S, erfa_site, observed_of_j2000
from scopelink.astro.refraction import RefractionModel
from scopelink.astro.site import Site
from scopelink.astro.timescales import ScalarTime, TimeLike, check_ut1_minus_utc, utc_pair

__all__ = [
    "altaz_to_hadec",
    "apparent_to_observed",
    "hadec_to_altaz",
    "j2000_to_observed",
    "observed_to_apparent",
    "observed_to_j2000",
]

_HOURS_PER_RADIAN = 12.0 / np.pi


_REUSE_WITHIN_DAYS = OBSERVER_REUSE_S / 86400.0


@dataclass(slots=True)
class _CachedObserver:
    site: Site
    ut1_minus_utc_s: float
    utc_jd: float
    astrom: Any
    equation_of_origins: FloatArray


_last_observer: _CachedObserver | None = None


def _observer(t: TimeLike, site: Site, ut1_minus_utc_s: float) -> tuple[Any, FloatArray]:
    """ERFA's star-independent context for ``site`` at ``t`` (refraction off) and EO.

    One instant at a time (a mount's poll) reuses the previous context when it is for the same
    site and within 10 s, updating only the Earth rotation: a fifth of the cost of ``apco13``."""
    global _last_observer  # noqa: PLW0603 - a one-entry cache of the most recent instant
    check_ut1_minus_utc(ut1_minus_utc_s)
    utc1, utc2 = utc_pair(t)
    if np.ndim(utc1) == 0:
        cached = _last_observer
        jd = float(utc1) + float(utc2)
        if (
            cached is not None
            and cached.site == site
            and cached.ut1_minus_utc_s == ut1_minus_utc_s
            and abs(jd - cached.utc_jd) <= _REUSE_WITHIN_DAYS
        ):
            ut11, ut12, status = erfa.ufunc.utcut1(utc1, utc2, ut1_minus_utc_s)
            if status:
                ut11, ut12 = erfa.utcut1(utc1, utc2, ut1_minus_utc_s)  # its warning or error
            # erfa.aper13's one change, the local Earth rotation angle ERA(UT1) + longitude, on
            # a copy: the dashboard's sky view converts in a worker thread meanwhile.
            astrom = cached.astrom.copy()
            astrom["eral"] = erfa.ufunc.era00(ut11, ut12) + astrom["along"]
            return astrom, cached.equation_of_origins
        astrom, equation_of_origins = _observer_now(utc1, utc2, site, ut1_minus_utc_s)
        _last_observer = _CachedObserver(site, ut1_minus_utc_s, jd, astrom, equation_of_origins)
        return astrom, equation_of_origins
    return _observer_now(utc1, utc2, site, ut1_minus_utc_s)


def _observer_now(
    utc1: FloatArray, utc2: FloatArray, site: Site, ut1_minus_utc_s: float
) -> tuple[Any, FloatArray]:
    astrom, equation_of_origins = erfa.apco13(utc1, utc2, ut1_minus_utc_s, *erfa_site(site))
    return astrom, as_float_array(equation_of_origins)


def _observed_from_cirs(
    cirs_ra: FloatArray, cirs_dec: FloatArray, astrom: Any, site: Site
) -> tuple[FloatOrArray, FloatOrArray]:
    azimuth, zenith_distance, *_ = erfa.atioq(cirs_ra, cirs_dec, astrom)
    return _refracted(azimuth, zenith_distance, site)


def _refracted(
    azimuth: FloatArray, zenith_distance: FloatArray, site: Site
) -> tuple[FloatOrArray, FloatOrArray]:
    true_altitude = 90.0 - np.degrees(zenith_distance)
    altitude = RefractionModel.for_site(site).refract(true_altitude)
    return scalar_or_array(altitude), wrap_degrees(np.degrees(azimuth))


def _one_observer(astrom: Any, positions: FloatArray) -> bool:
    """Whether the vector path applies: one instant (one context) and an array of positions."""
    return bool(astrom.ndim == 0 and positions.ndim > 0)


def _observed_from_vectors(
    cirs: FloatArray, astrom: Any, site: Site
) -> tuple[FloatOrArray, FloatOrArray]:
    """``erfa.atioq`` (refraction off) for CIRS unit vectors ``(..., 3)`` at one instant.

    The same arithmetic as ERFA, with the Earth rotation and polar motion folded into one
    matrix and none of atioq's unused outputs (observed HA, Dec, RA) or its CIRS RA/Dec
    round trip: a third of its cost for 10,000 positions. Equal to atioq to 1e-9 arcsec
    (``tests/astro/test_astro_fast_path.py``)."""
    x, y, z = np.moveaxis(cirs @ _earth_rotation(astrom).T, -1, 0)
    diurnal = float(astrom["diurab"])
    shrink = 1.0 - diurnal * y
    x_hd, y_hd, z_hd = shrink * x, shrink * (y + diurnal), shrink * z
    sin_phi, cos_phi = float(astrom["sphi"]), float(astrom["cphi"])
    x_ae = sin_phi * x_hd - cos_phi * z_hd
    z_ae = cos_phi * x_hd + sin_phi * z_hd
    azimuth = np.arctan2(y_hd, -x_ae)
    zenith_distance = np.arctan2(np.hypot(x_ae, y_hd), z_ae)
    return _refracted(azimuth, zenith_distance, site)


def _earth_rotation(astrom: Any) -> FloatArray:
    """CIRS -> Cartesian (-HA, Dec) of the site: polar motion after the local Earth rotation."""
    cos_era, sin_era = np.cos(astrom["eral"]), np.sin(astrom["eral"])
    sin_x, cos_x = np.sin(astrom["xpl"]), np.cos(astrom["xpl"])
    sin_y, cos_y = np.sin(astrom["ypl"]), np.cos(astrom["ypl"])
    rotation = np.array([[cos_era, sin_era, 0.0], [-sin_era, cos_era, 0.0], [0.0, 0.0, 1.0]])
    polar_motion = np.array(
        [
            [cos_x, 0.0, sin_x],
            [sin_x * sin_y, cos_y, -cos_x * sin_y],
            [-sin_x * cos_y, sin_y, cos_x * cos_y],
        ]
    )
    matrix: FloatArray = polar_motion @ rotation
    return matrix


def _cirs_from_observed(
    alt_deg: npt.ArrayLike, az_deg: npt.ArrayLike, astrom: Any, site: Site
) -> tuple[FloatArray, FloatArray]:
    true_altitude = RefractionModel.for_site(site).unrefract(alt_deg)
    zenith_distance = np.radians(90.0 - true_altitude)
    cirs_ra, cirs_dec = erfa.atoiq("A", np.radians(as_float_array(az_deg)), zenith_distance, astrom)
    return as_float_array(cirs_ra), as_float_array(cirs_dec)


@overload
def j2000_to_observed(
    ra_hours: float, dec_deg: float, t: ScalarTime, site: Site, *, ut1_minus_utc_s: float = 0.0
) -> tuple[float, float]: ...
@overload
def j2000_to_observed(
    ra_hours: npt.ArrayLike,
    dec_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]: ...
def j2000_to_observed(
    ra_hours: npt.ArrayLike,
    dec_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]:
    """J2000 (ICRS) RA/Dec -> observed (altitude, azimuth) in degrees at ``site``."""
    ra_one: object = ra_hours
    dec_one: object = dec_deg
    if isinstance(ra_one, float) and isinstance(dec_one, float) and isinstance(t, datetime):
        check_ut1_minus_utc(ut1_minus_utc_s)
        return observed_of_j2000(ra_one, dec_one, t, site, ut1_minus_utc_s)  # a poll's
    astrom, _ = _observer(t, site, ut1_minus_utc_s)
    ra, dec = radec_radians(ra_hours, dec_deg)
    if _one_observer(astrom, ra) or _one_observer(astrom, dec):
        # erfa.atciqz on vectors, without its C2s/S2c round trip into atioq.
        natural = erfa.ldsun(erfa.s2c(ra, dec), astrom["eh"], astrom["em"])
        proper = erfa.ab(natural, astrom["v"], astrom["em"], astrom["bm1"])
        return _observed_from_vectors(proper @ astrom["bpn"].T, astrom, site)
    return _reference_j2000_to_observed(ra, dec, astrom, site)


def _reference_j2000_to_observed(
    ra: FloatArray, dec: FloatArray, astrom: Any, site: Site
) -> tuple[FloatOrArray, FloatOrArray]:
    """ERFA's own atciqz + atioq: the path for one position or many instants, and the
    reference the vector path is tested against."""
    cirs_ra, cirs_dec = erfa.atciqz(ra, dec, astrom)
    return _observed_from_cirs(cirs_ra, cirs_dec, astrom, site)


@overload
def observed_to_j2000(
    alt_deg: float, az_deg: float, t: ScalarTime, site: Site, *, ut1_minus_utc_s: float = 0.0
) -> tuple[float, float]: ...
@overload
def observed_to_j2000(
    alt_deg: npt.ArrayLike,
    az_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]: ...
def observed_to_j2000(
    alt_deg: npt.ArrayLike,
    az_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]:
    """Observed (altitude, azimuth) in degrees at ``site`` -> J2000 (ICRS) (RA hours, Dec deg)."""
    astrom, _ = _observer(t, site, ut1_minus_utc_s)
    cirs_ra, cirs_dec = _cirs_from_observed(alt_deg, az_deg, astrom, site)
    return radec_public(*erfa.aticq(cirs_ra, cirs_dec, astrom))


@overload
def apparent_to_observed(
    ra_hours: float, dec_deg: float, t: ScalarTime, site: Site, *, ut1_minus_utc_s: float = 0.0
) -> tuple[float, float]: ...
@overload
def apparent_to_observed(
    ra_hours: npt.ArrayLike,
    dec_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]: ...
def apparent_to_observed(
    ra_hours: npt.ArrayLike,
    dec_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]:
    """Apparent RA/Dec of date -> observed (altitude, azimuth) in degrees at ``site``."""
    astrom, equation_of_origins = _observer(t, site, ut1_minus_utc_s)
    ra, dec = radec_radians(ra_hours, dec_deg)
    if _one_observer(astrom, ra) or _one_observer(astrom, dec):
        return _observed_from_vectors(erfa.s2c(ra + equation_of_origins, dec), astrom, site)
    return _observed_from_cirs(ra + equation_of_origins, dec, astrom, site)


@overload
def observed_to_apparent(
    alt_deg: float, az_deg: float, t: ScalarTime, site: Site, *, ut1_minus_utc_s: float = 0.0
) -> tuple[float, float]: ...
@overload
def observed_to_apparent(
    alt_deg: npt.ArrayLike,
    az_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]: ...
def observed_to_apparent(
    alt_deg: npt.ArrayLike,
    az_deg: npt.ArrayLike,
    t: TimeLike,
    site: Site,
    *,
    ut1_minus_utc_s: float = 0.0,
) -> tuple[FloatOrArray, FloatOrArray]:
    """Observed (altitude, azimuth) in degrees at ``site`` -> apparent RA/Dec of date."""
    astrom, equation_of_origins = _observer(t, site, ut1_minus_utc_s)
    cirs_ra, cirs_dec = _cirs_from_observed(alt_deg, az_deg, astrom, site)
    return radec_public(cirs_ra - equation_of_origins, cirs_dec)


@overload
def hadec_to_altaz(ha_hours: float, dec_deg: float, latitude_deg: float) -> tuple[float, float]: ...
@overload
def hadec_to_altaz(
    ha_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, latitude_deg: npt.ArrayLike
) -> tuple[FloatOrArray, FloatOrArray]: ...
def hadec_to_altaz(
    ha_hours: npt.ArrayLike, dec_deg: npt.ArrayLike, latitude_deg: npt.ArrayLike
) -> tuple[FloatOrArray, FloatOrArray]:
    """Hour angle/Dec -> (altitude, azimuth) in degrees: pure rotation, no refraction."""
    values: tuple[object, ...] = (ha_hours, dec_deg, latitude_deg)
    if all(isinstance(value, float) for value in values):
        return _hadec_to_altaz_one(float(ha_hours), float(dec_deg), float(latitude_deg))  # type: ignore[arg-type]
    azimuth, elevation = erfa.hd2ae(
        as_float_array(ha_hours) / _HOURS_PER_RADIAN,
        np.radians(as_float_array(dec_deg)),
        np.radians(as_float_array(latitude_deg)),
    )
    return scalar_or_array(np.degrees(elevation)), wrap_degrees(np.degrees(azimuth))


def _hadec_to_altaz_one(
    ha_hours: float, dec_deg: float, latitude_deg: float
) -> tuple[float, float]:
    """One position (a poll's): ``erfa.hd2ae``'s C code in Python floats, term for term, so the
    same doubles (tested bit for bit) at a quarter of the ufunc's cost."""
    ha, dec, phi = ha_hours / _HOURS_PER_RADIAN, math.radians(dec_deg), math.radians(latitude_deg)
    sin_h, cos_h = math.sin(ha), math.cos(ha)
    sin_d, cos_d = math.sin(dec), math.cos(dec)
    sin_p, cos_p = math.sin(phi), math.cos(phi)
    x = -cos_h * cos_d * sin_p + sin_d * cos_p
    y = -sin_h * cos_d
    z = cos_h * cos_d * cos_p + sin_d * sin_p
    r = math.sqrt(x * x + y * y)
    angle = math.atan2(y, x) if r != 0.0 else 0.0
    azimuth = angle + 2.0 * math.pi if angle < 0.0 else angle
    return math.degrees(math.atan2(z, r)), wrap_degrees(math.degrees(azimuth))


@overload
def altaz_to_hadec(alt_deg: float, az_deg: float, latitude_deg: float) -> tuple[float, float]: ...
@overload
def altaz_to_hadec(
    alt_deg: npt.ArrayLike, az_deg: npt.ArrayLike, latitude_deg: npt.ArrayLike
) -> tuple[FloatOrArray, FloatOrArray]: ...
def altaz_to_hadec(
    alt_deg: npt.ArrayLike, az_deg: npt.ArrayLike, latitude_deg: npt.ArrayLike
) -> tuple[FloatOrArray, FloatOrArray]:
    """(Altitude, azimuth) in degrees -> (hour angle in [-12, 12) h, Dec degrees): pure rotation."""
    hour_angle, declination = erfa.ae2hd(
        np.radians(as_float_array(az_deg)),
        np.radians(as_float_array(alt_deg)),
        np.radians(as_float_array(latitude_deg)),
    )
    return (
        wrap_hour_angle(as_float_array(hour_angle) * _HOURS_PER_RADIAN),
        scalar_or_array(np.degrees(declination)),
    )
