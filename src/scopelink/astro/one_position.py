"""One J2000 position at one instant, in Python floats: what a mount's poll converts.

numpy and ERFA's ufuncs cost microseconds per call on single floats, which is most of the cost
of converting one reading. Here the star-independent part is computed by ERFA once and kept as
floats for 10 s: the geocentric context (``erfa.apci13``: precession-nutation, the Earth's
position and velocity) and the site's (``erfa.apio13``: Earth rotation, polar motion, diurnal
aberration), its Earth rotation angle advanced in closed form. The star-dependent steps are
ERFA's own, written out in floats: light deflection by the Sun, annual aberration and
bias-precession-nutation to CIRS (``erfa.atciqz``), then Earth rotation, polar motion, diurnal
aberration and the horizon frame (``erfa.atioq``); refraction is
:class:`~scopelink.astro.refraction.RefractionModel`'s. One reading's CIRS direction serves both
its alt/az and its RA/Dec of date.

This is ERFA's CIRS route to the observed place (``atci13`` + ``atio13``); the array path goes
through the site's own context (``apco13``: the site's velocity in the annual aberration). The two
differ by second-order terms of the two aberrations, 0.2 mas at most;
``tests/astro/test_astro_one_position.py`` holds them within 1 mas of each other.

:func:`~scopelink.astro.j2000_to_observed` and :func:`~scopelink.astro.j2000_to_apparent` come
here for one float position at one aware ``datetime``; anything else takes the array path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import erfa
import numpy as np

from scopelink.astro.refraction import RefractionModel
from scopelink.astro.site import Site
from scopelink.astro.timescales import seconds_of_utc_day, tt_pair, utc_day_seconds

__all__ = [
    "GEOCENTRIC_REUSE_S",
    "OBSERVER_REUSE_S",
    "apparent_of_j2000",
    "erfa_site",
    "observed_of_j2000",
    "reading_of_j2000",
]

GEOCENTRIC_REUSE_S = 1.0
"""The array path's geocentric context (``frames``) serves instants up to 1 s away unchanged: in
1 s precession moves 2e-6 arcsec, nutation 1e-6, annual aberration 4e-6. It has no Earth
rotation in it, so one context serves every site."""
OBSERVER_REUSE_S = 10.0
"""A context serves instants up to 10 s away, the Earth rotation angle advanced (as
``erfa.aper13`` does): the array path's observer context (``horizontal``) and both of this
module's. In 10 s precession moves 2e-5 arcsec, nutation 3e-5, annual aberration 4e-5 and the
site's velocity less: well under a milliarcsecond."""

_SCHWARZSCHILD_AU = erfa.SRS
"""The Sun's Schwarzschild radius in au (ERFA's constant, for deflection and aberration)."""
_ERA_RAD_PER_UT1_S = 2.0 * math.pi * 1.00273781191135448 / 86400.0
"""The Earth rotation angle's rate (IAU 2000, ``erfa.era00``): radians per second of UT1."""
_RADIANS_PER_HOUR = math.pi / 12.0

_Vector = tuple[float, float, float]
_Matrix = tuple[float, float, float, float, float, float, float, float, float]


@dataclass(frozen=True, slots=True)
class _Natural:
    """What turns a catalogue direction into one of date (``erfa.atciqz``'s inputs)."""

    sun: _Vector
    """Heliocentric direction of the observer (``eh``)."""
    sun_au: float
    """Its distance from the Sun in au (``em``)."""
    deflection_floor: float
    """ERFA's lower limit for the deflection's denominator near the Sun (``eraLdsun``)."""
    velocity: _Vector
    """The observer's barycentric velocity in units of c (``v``)."""
    inverse_lorentz: float
    """The reciprocal of its Lorentz factor (``bm1``)."""
    bpn: _Matrix
    """Bias-precession-nutation, row by row (``bpn``)."""

    @classmethod
    def of(cls, astrom: Any) -> _Natural:
        sun_au = float(astrom["em"])
        sun_squared = max(sun_au * sun_au, 1.0)
        return cls(
            _vector(astrom["eh"]),
            sun_au,
            1e-6 / sun_squared,
            _vector(astrom["v"]),
            float(astrom["bm1"]),
            _matrix(astrom["bpn"]),
        )

    def of_date(self, ra_hours: float, dec_deg: float) -> _Vector:
        """The unit vector of a J2000 (ICRS) position in the intermediate frame of date (CIRS):
        light deflection by the Sun, annual aberration, then bias-precession-nutation; NaNs for
        a position that is not finite (as the array path gives)."""
        if not (math.isfinite(ra_hours) and math.isfinite(dec_deg)):
            return math.nan, math.nan, math.nan
        ra, dec = ra_hours * _RADIANS_PER_HOUR, math.radians(dec_deg)
        cos_dec = math.cos(dec)
        px, py, pz = math.cos(ra) * cos_dec, math.sin(ra) * cos_dec, math.sin(dec)
        # Light deflection by the Sun (eraLdsun: eraLd with the body the Sun, q = p).
        ex, ey, ez = self.sun
        sun_au = self.sun_au
        q_dot = px * (px + ex) + py * (py + ey) + pz * (pz + ez)
        w = _SCHWARZSCHILD_AU / sun_au / max(q_dot, self.deflection_floor)
        # e x q, then p x (e x q)
        eqx, eqy, eqz = ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px
        nx = px + w * (py * eqz - pz * eqy)
        ny = py + w * (pz * eqx - px * eqz)
        nz = pz + w * (px * eqy - py * eqx)
        # Annual aberration (eraAb).
        vx, vy, vz = self.velocity
        bm1 = self.inverse_lorentz
        p_dot_v = nx * vx + ny * vy + nz * vz
        w1 = 1.0 + p_dot_v / (1.0 + bm1)
        w2 = _SCHWARZSCHILD_AU / sun_au
        ax = nx * bm1 + w1 * vx + w2 * (vx - p_dot_v * nx)
        ay = ny * bm1 + w1 * vy + w2 * (vy - p_dot_v * ny)
        az = nz * bm1 + w1 * vz + w2 * (vz - p_dot_v * nz)
        norm = math.sqrt(ax * ax + ay * ay + az * az)
        ax, ay, az = ax / norm, ay / norm, az / norm
        m = self.bpn
        return (
            m[0] * ax + m[1] * ay + m[2] * az,
            m[3] * ax + m[4] * ay + m[5] * az,
            m[6] * ax + m[7] * ay + m[8] * az,
        )


def _vector(values: Any) -> _Vector:
    x, y, z = np.asarray(values, dtype=np.float64).reshape(3).tolist()
    return x, y, z


def _matrix(values: Any) -> _Matrix:
    a, b, c, d, e, f, g, h, i = np.asarray(values, dtype=np.float64).reshape(9).tolist()
    return a, b, c, d, e, f, g, h, i


# --- the geocentric context: apparent RA/Dec of date -----------------------------------------


@dataclass(frozen=True, slots=True)
class _Geocentric:
    day_jd: float
    seconds: float
    natural: _Natural
    equation_of_origins: float


_last_geocentric: _Geocentric | None = None


def _geocentric(moment: datetime, day_jd: float, seconds: float) -> _Geocentric:
    """The geocentric context serving ``moment`` (``day_jd``, ``seconds``: its UTC day and
    seconds, :func:`~scopelink.astro.timescales.utc_day_seconds`)."""
    global _last_geocentric  # noqa: PLW0603 - a one-entry cache of the most recent instant
    cached = _last_geocentric
    if (
        cached is not None
        and cached.day_jd == day_jd
        and abs(seconds - cached.seconds) <= OBSERVER_REUSE_S
    ):
        return cached
    astrom, equation_of_origins = erfa.apci13(*tt_pair(moment))
    cached = _Geocentric(day_jd, seconds, _Natural.of(astrom), float(equation_of_origins))
    _last_geocentric = cached
    return cached


@dataclass(frozen=True, slots=True)
class _Place:
    """One J2000 position in one geocentric context: its CIRS direction and its apparent RA/Dec
    of date, computed together once (a poll's reading asks for both, and the same position is
    read again and again while the mount stands still or the Sky Commander's last digit holds)."""

    ra_hours: float
    dec_deg: float
    context: _Geocentric
    x: float
    y: float
    z: float
    ra_of_date_hours: float
    dec_of_date_deg: float

    @classmethod
    def of(cls, ra_hours: float, dec_deg: float, context: _Geocentric) -> _Place:
        x, y, z = context.natural.of_date(ra_hours, dec_deg)
        across = x * x + y * y
        ra = math.atan2(y, x) if across != 0.0 else 0.0
        dec = math.atan2(z, math.sqrt(across)) if z != 0.0 else 0.0
        hours = ((ra - context.equation_of_origins) / _RADIANS_PER_HOUR) % 24.0
        ra_of_date = 0.0 if hours >= 24.0 else hours
        return cls(ra_hours, dec_deg, context, x, y, z, ra_of_date, math.degrees(dec))


_last_place: _Place | None = None


def _place(ra_hours: float, dec_deg: float, context: _Geocentric) -> _Place:
    """The position in ``context``: kept for the next call with the same position and context
    (its alt/az and RA/Dec of date, and the next poll's while the reading holds)."""
    global _last_place  # noqa: PLW0603 - a one-entry cache: the reading of the last poll
    last = _last_place
    if (
        last is not None
        and last.context is context
        and last.ra_hours == ra_hours
        and last.dec_deg == dec_deg
    ):
        return last
    place = _last_place = _Place.of(ra_hours, dec_deg, context)
    return place


def apparent_of_j2000(ra_hours: float, dec_deg: float, moment: datetime) -> tuple[float, float]:
    """Apparent RA (hours, [0, 24)) and Dec (degrees) of date of one J2000 position at
    ``moment``: :func:`~scopelink.astro.j2000_to_apparent` in floats."""
    day_jd, seconds, _ = utc_day_seconds(moment)
    place = _place(ra_hours, dec_deg, _geocentric(moment, day_jd, seconds))
    return place.ra_of_date_hours, place.dec_of_date_deg


# --- the observer's context: observed alt/az --------------------------------------------------


def erfa_site(site: Site) -> tuple[float, ...]:
    """``site`` as ERFA's observer contexts (``apco13``, ``apio13``) take it after the time and
    DUT1: longitude and latitude in radians, height, no polar motion, no pressure (ERFA's
    refraction off: ours is applied to the altitude), temperature, humidity, wavelength."""
    return (
        math.radians(site.longitude_deg),
        math.radians(site.latitude_deg),
        site.elevation_m,
        0.0,  # polar motion x
        0.0,  # polar motion y
        0.0,  # pressure
        site.temperature_c,
        site.relative_humidity,
        site.wavelength_um,
    )


@dataclass(frozen=True, slots=True)
class _Observer:
    site: Site
    ut1_minus_utc_s: float
    utc_date: tuple[int, int, int]
    """The UTC day (year, month, day) of ``day_jd``."""
    day_jd: float
    seconds: float
    local_era: float
    """The local Earth rotation angle (ERA + longitude) at ``seconds``."""
    polar_motion: _Matrix | None
    """None without polar motion (the identity)."""
    diurnal: float
    """The site's speed about the Earth's axis in units of c (``erfa.apio13``'s ``diurab``)."""
    sin_latitude: float
    cos_latitude: float
    refraction: RefractionModel

    @classmethod
    def at(cls, moment: datetime, site: Site, ut1_minus_utc_s: float) -> _Observer:
        day_jd, seconds, day_seconds = utc_day_seconds(moment)
        utc = moment.astimezone(UTC)
        astrom = erfa.apio13(day_jd, seconds / day_seconds, ut1_minus_utc_s, *erfa_site(site))
        xpl, ypl = float(astrom["xpl"]), float(astrom["ypl"])
        sin_x, cos_x, sin_y, cos_y = math.sin(xpl), math.cos(xpl), math.sin(ypl), math.cos(ypl)
        polar_motion: _Matrix | None = (
            None  # none given (erfa_site): the identity, skipped
            if xpl == 0.0 and ypl == 0.0
            else (
                cos_x,
                0.0,
                sin_x,
                sin_x * sin_y,
                cos_y,
                -cos_x * sin_y,
                -sin_x * cos_y,
                sin_y,
                cos_x * cos_y,
            )
        )
        return cls(
            site,
            ut1_minus_utc_s,
            (utc.year, utc.month, utc.day),
            day_jd,
            seconds,
            float(astrom["eral"]),
            polar_motion,
            float(astrom["diurab"]),
            float(astrom["sphi"]),
            float(astrom["cphi"]),
            RefractionModel.for_site(site),
        )


_last_observer: _Observer | None = None


def _observer(
    moment: datetime, day_jd: float, seconds: float, site: Site, ut1_minus_utc_s: float
) -> _Observer:
    """The site's context serving ``moment`` (``day_jd``, ``seconds`` as for _geocentric)."""
    global _last_observer  # noqa: PLW0603 - a one-entry cache of the most recent instant
    cached = _last_observer
    if (
        cached is None
        or cached.day_jd != day_jd
        or abs(seconds - cached.seconds) > OBSERVER_REUSE_S
        or (cached.site is not site and cached.site != site)
        or cached.ut1_minus_utc_s != ut1_minus_utc_s
    ):
        cached = _Observer.at(moment, site, ut1_minus_utc_s)
        _last_observer = cached
    return cached


def observed_of_j2000(
    ra_hours: float, dec_deg: float, moment: datetime, site: Site, ut1_minus_utc_s: float
) -> tuple[float, float]:
    """Observed (altitude, azimuth) in degrees of one J2000 position at ``moment`` and
    ``site``: :func:`~scopelink.astro.j2000_to_observed` in floats (``ut1_minus_utc_s`` checked
    by the caller)."""
    day_jd, seconds, _ = utc_day_seconds(moment)
    place = _place(ra_hours, dec_deg, _geocentric(moment, day_jd, seconds))
    return _horizon(place, _observer(moment, day_jd, seconds, site, ut1_minus_utc_s), seconds)


def reading_of_j2000(
    ra_hours: float, dec_deg: float, moment: datetime, site: Site
) -> tuple[float, float, float, float]:
    """Observed (altitude, azimuth) in degrees and apparent RA (hours) and Dec (degrees) of date
    of one J2000 position at ``moment`` and ``site`` (DUT1 0, as a mount's clock is UTC): what
    a mount's poll derives from its reading, in one pass (one time conversion and one look-up
    of each context; :func:`observed_of_j2000` and :func:`apparent_of_j2000` give the same
    values)."""
    # The common case of a poll, inline: the reading of the last call (a mount standing still,
    # or tracking: the Sky Commander's last digit holds) on the same UTC day, both contexts
    # still serving: the contexts and place the look-ups below would find, so the same doubles,
    # ~90 bytecodes fewer per poll (issue #14).
    place, observer = _last_place, _last_observer
    if (
        place is not None
        and observer is not None
        and moment.tzinfo is UTC
        and place.ra_hours == ra_hours
        and place.dec_deg == dec_deg
        and place.context is _last_geocentric
        and observer.site is site
        and observer.ut1_minus_utc_s == 0.0
        and observer.utc_date == (moment.year, moment.month, moment.day)
        and place.context.day_jd == observer.day_jd
    ):
        seconds = seconds_of_utc_day(moment)
        if (
            abs(seconds - observer.seconds) <= OBSERVER_REUSE_S
            and abs(seconds - place.context.seconds) <= OBSERVER_REUSE_S
        ):
            alt, az = _horizon(place, observer, seconds)
            return alt, az, place.ra_of_date_hours, place.dec_of_date_deg
    day_jd, seconds, _ = utc_day_seconds(moment)
    place = _place(ra_hours, dec_deg, _geocentric(moment, day_jd, seconds))
    observer = _observer(moment, day_jd, seconds, site, 0.0)
    alt, az = _horizon(place, observer, seconds)
    return alt, az, place.ra_of_date_hours, place.dec_of_date_deg


def _horizon(place: _Place, context: _Observer, seconds: float) -> tuple[float, float]:
    """Observed (altitude, azimuth) of ``place`` at UTC ``seconds`` of the observer context's
    day: Earth rotation, polar motion, diurnal aberration, the horizon frame, refraction."""
    # Within one UTC day UT1 advances with UTC's seconds (utc_day_seconds): ERA is linear in it.
    era = context.local_era + _ERA_RAD_PER_UT1_S * (seconds - context.seconds)
    cos_era, sin_era = math.cos(era), math.sin(era)
    x, y, z = place.x, place.y, place.z
    x, y = cos_era * x + sin_era * y, cos_era * y - sin_era * x  # CIRS -> (-HA, Dec)
    m = context.polar_motion
    if m is not None:
        x, y, z = (
            m[0] * x + m[1] * y + m[2] * z,
            m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z,
        )
    diurnal = context.diurnal
    shrink = 1.0 - diurnal * y
    x, y, z = shrink * x, shrink * (y + diurnal), shrink * z
    sin_phi, cos_phi = context.sin_latitude, context.cos_latitude
    x_ae = sin_phi * x - cos_phi * z
    z_ae = cos_phi * x + sin_phi * z
    azimuth = math.atan2(y, -x_ae) if (x_ae != 0.0 or y != 0.0) else 0.0
    zenith_distance = math.atan2(math.sqrt(x_ae * x_ae + y * y), z_ae)
    altitude = context.refraction.refract_scalar_deg(90.0 - math.degrees(zenith_distance))
    degrees = math.degrees(azimuth) % 360.0
    return altitude, (0.0 if degrees >= 360.0 else degrees)
