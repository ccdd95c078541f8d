"""Rise, transit and set, and "is it up now", for any catalogue object at a site.

Altitudes are sampled every few minutes over the window, then each crossing is refined by
bisection to well under a second. The horizon follows the almanac convention unless a horizon is
given (see :func:`rise_transit_set`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta

import erfa
import numpy as np

from scopelink.astro._arrays import FloatArray
from scopelink.astro.angles import wrap_hour_angle
from scopelink.astro.catalog.entries import CatalogEntry, FixedPosition, Prominence
from scopelink.astro.catalog.index import default_catalogue
from scopelink.astro.catalog.objects import ObjectKind
from scopelink.astro.frames import j2000_to_apparent
from scopelink.astro.horizontal import j2000_to_observed
from scopelink.astro.sidereal import lst_hours
from scopelink.astro.site import Site
from scopelink.astro.timescales import ScalarTime, utc_pair

__all__ = [
    "STANDARD_HORIZON_DEG",
    "SUN_MOON_HORIZON_DEG",
    "RiseTransitSet",
    "Target",
    "is_up",
    "rise_transit_set",
]

STANDARD_HORIZON_DEG = -34.0 / 60.0
"""Geometric altitude of a point at the horizon seen through standard air (34' refraction)."""

SUN_MOON_HORIZON_DEG = -50.0 / 60.0
"""Geometric altitude of the centre when the upper limb touches the horizon: 34' + 16'."""

_SAMPLE_STEP_DAYS = 5.0 / 1440.0
_BISECTIONS = 14  # 5 min / 2**14 = 0.02 s

Target = str | CatalogEntry | tuple[float, float]
"""A catalogue name, a catalogue entry, or fixed J2000 (RA hours, Dec degrees)."""

_Function = Callable[[FloatArray, FloatArray], FloatArray]


@dataclass(frozen=True, slots=True)
class RiseTransitSet:
    """The first rise, upper transit and set in the window (aware UTC), None when none occurs.

    ``always_up`` / ``never_up`` say why rise and set are None when the object stayed above
    or below the horizon for the whole window (circumpolar or never rising).
    """

    rise: datetime | None
    transit: datetime | None
    set: datetime | None
    always_up: bool
    never_up: bool


def _entry(target: Target) -> CatalogEntry:
    if isinstance(target, CatalogEntry):
        return target
    if isinstance(target, str):
        return default_catalogue().find(target)
    ra_hours, dec_deg = target
    return CatalogEntry(
        name=f"RA {ra_hours:.4f}h Dec {dec_deg:+.4f}°",
        aliases=(),
        kind=ObjectKind.STAR,
        type_description="Fixed position",
        magnitude=None,
        constellation=None,
        position=FixedPosition(ra_hours, dec_deg),
        prominence=Prominence.OTHER,
    )


def _altitude_above_horizon(
    entry: CatalogEntry, site: Site, horizon_deg: float | None
) -> _Function:
    """Altitude minus the horizon, as a function of UTC (jd1, jd2) arrays."""
    if horizon_deg is None:
        observing_site = site.without_refraction()
        uses_limb = entry.kind in (ObjectKind.SUN, ObjectKind.MOON)
        threshold = SUN_MOON_HORIZON_DEG if uses_limb else STANDARD_HORIZON_DEG
    else:
        observing_site, threshold = site, horizon_deg

    def altitude(jd1: FloatArray, jd2: FloatArray) -> FloatArray:
        ra, dec, _ = entry.position.astrometric((jd1, jd2), site)
        alt, _ = j2000_to_observed(ra, dec, (jd1, jd2), observing_site)
        return np.asarray(alt, dtype=np.float64) - threshold

    return altitude


def _hour_angle(entry: CatalogEntry, site: Site) -> _Function:
    """Local apparent hour angle in [-12, 12) h, as a function of UTC (jd1, jd2) arrays."""

    def hour_angle(jd1: FloatArray, jd2: FloatArray) -> FloatArray:
        ra, dec, _ = entry.position.astrometric((jd1, jd2), site)
        apparent_ra, _ = j2000_to_apparent(ra, dec, (jd1, jd2))
        local_sidereal = lst_hours((jd1, jd2), site.longitude_deg)
        return np.asarray(wrap_hour_angle(np.asarray(local_sidereal) - apparent_ra))

    return hour_angle


def _first_upward_crossing(
    function: _Function, jd1: FloatArray, jd2: FloatArray, values: FloatArray
) -> float | None:
    """jd2 of the first sign change from below 0 to at or above 0, refined by bisection."""
    crossings = np.flatnonzero((values[:-1] < 0.0) & (values[1:] >= 0.0))
    if crossings.size == 0:
        return None
    index = int(crossings[0])
    low, high = float(jd2[index]), float(jd2[index + 1])
    day = jd1[:1]
    for _ in range(_BISECTIONS):
        middle = 0.5 * (low + high)
        if function(day, np.array([middle]))[0] < 0.0:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def _utc_datetime(jd1: float, jd2: float) -> datetime:
    year, month, day, hmsf = erfa.d2dtf("UTC", 3, jd1, jd2)
    hours, minutes, seconds, milliseconds = (int(x) for x in hmsf.item())
    start_of_day = datetime(int(year), int(month), int(day), tzinfo=UTC)
    return start_of_day + timedelta(
        hours=hours, minutes=minutes, seconds=seconds, milliseconds=milliseconds
    )


def rise_transit_set(
    target: Target,
    site: Site,
    start: ScalarTime,
    *,
    window_hours: float = 24.0,
    horizon_deg: float | None = None,
) -> RiseTransitSet:
    """The first rise, upper transit and set of ``target`` at ``site`` after ``start``.

    Horizon: by default the almanac convention on the geometric (airless) altitude of the
    centre, whatever the site's air: -34' for stars, planets and fixed positions (standard
    refraction at the horizon), -50' for the Sun and Moon (upper limb: 34' + 16' semidiameter;
    the Moon's position is topocentric, so its parallax is already in). With ``horizon_deg``
    the centre's *observed* altitude, refracted by the site's air, must reach that altitude
    (e.g. 15 for a tree line). Events closer together than the 5-minute sampling (an object
    grazing the horizon) may be missed.
    """
    entry = _entry(target)
    start_jd1, start_jd2 = (float(part) for part in utc_pair(start))
    offsets = np.arange(0.0, window_hours / 24.0 + _SAMPLE_STEP_DAYS, _SAMPLE_STEP_DAYS)
    offsets = np.minimum(offsets, window_hours / 24.0)
    jd1 = np.full(offsets.shape, start_jd1)
    jd2 = start_jd2 + offsets

    above = _altitude_above_horizon(entry, site, horizon_deg)
    altitudes = above(jd1, jd2)

    def below(day: FloatArray, fraction: FloatArray) -> FloatArray:
        return -above(day, fraction)

    hour_angle = _hour_angle(entry, site)
    hour_angles = hour_angle(jd1, jd2)
    # A -12 -> +12 wrap is lower culmination, not transit: keep only small steps through 0.
    hour_angles = np.where(np.abs(hour_angles) < 6.0, hour_angles, np.nan)

    def event(found: float | None) -> datetime | None:
        return None if found is None else _utc_datetime(start_jd1, found)

    return RiseTransitSet(
        rise=event(_first_upward_crossing(above, jd1, jd2, altitudes)),
        transit=event(_first_upward_crossing(hour_angle, jd1, jd2, hour_angles)),
        set=event(_first_upward_crossing(below, jd1, jd2, -altitudes)),
        always_up=bool(np.all(altitudes >= 0.0)),
        never_up=bool(np.all(altitudes < 0.0)),
    )


def is_up(target: Target, site: Site, t: ScalarTime, *, horizon_deg: float | None = None) -> bool:
    """Whether ``target`` is above the horizon at ``t`` (same horizon rule as rise/set)."""
    entry = _entry(target)
    jd1, jd2 = (np.atleast_1d(part) for part in utc_pair(t))
    return bool(_altitude_above_horizon(entry, site, horizon_deg)(jd1, jd2)[0] >= 0.0)
