"""The information strip: the mount's clock, local sidereal time, Sun and Moon altitude and the
twilight phase, computed on the server (where the astronomy lives) for the page to show.

Times are the mount's (``mount.now()``: a simulator may run its own, faster clock). The twilight
phase is the Sun's geometric altitude (no refraction) against the usual boundaries: day above
-0.833° (upper limb on the horizon), civil to -6°, nautical to -12°, astronomical to -18°, night
below. Altitudes shown are observed (refracted), as everywhere else on the page.
"""

from __future__ import annotations

from datetime import datetime

import numpy as np

from scopelink.astro import Site, j2000_to_observed, lst_hours
from scopelink.astro.catalog import SUN_MOON_HORIZON_DEG, EphemerisRangeError, find

__all__ = ["TWILIGHT_BOUNDARIES_DEG", "clock_json", "twilight_json", "twilight_phase"]

TWILIGHT_BOUNDARIES_DEG = (
    (SUN_MOON_HORIZON_DEG, "day"),
    (-6.0, "civil twilight"),
    (-12.0, "nautical twilight"),
    (-18.0, "astronomical twilight"),
)
"""The Sun's geometric altitude above which each phase holds (below the last: night)."""


def twilight_phase(sun_geometric_alt_deg: float) -> str:
    """The phase for the Sun's geometric altitude: day, civil/nautical/astronomical twilight,
    or night."""
    for boundary, phase in TWILIGHT_BOUNDARIES_DEG:
        if sun_geometric_alt_deg > boundary:
            return phase
    return "night"


def twilight_json() -> dict[str, float]:
    """The boundaries by phase (the live connection's hello, ``twilight_deg``): the chart dims
    the sky from them, so the page holds no copy of these numbers."""
    return {phase: boundary for boundary, phase in TWILIGHT_BOUNDARIES_DEG}


def _sun_and_moon(t: datetime, site: Site) -> tuple[list[float], list[float]] | None:
    try:
        positions = [find(name).position.astrometric(t, site) for name in ("Sun", "Moon")]
    except EphemerisRangeError:
        return None
    ras = np.array([float(ra) for ra, _, _ in positions])
    decs = np.array([float(dec) for _, dec, _ in positions])
    observed, _ = j2000_to_observed(ras, decs, t, site)
    geometric, _ = j2000_to_observed(ras, decs, t, site.without_refraction())
    return [float(a) for a in np.atleast_1d(observed)], [float(a) for a in np.atleast_1d(geometric)]


def clock_json(now: datetime, site: Site) -> dict[str, object]:
    """``utc`` (ISO), ``lst_hours``, ``sun_alt``/``moon_alt`` (observed degrees) and
    ``twilight`` at ``now``; the Sun and Moon are None outside the ephemeris (1900-2200)."""
    clock: dict[str, object] = {
        "utc": now.isoformat(),
        "lst_hours": round(float(lst_hours(now, site.longitude_deg)), 6),
        "sun_alt": None,
        "moon_alt": None,
        "twilight": None,
    }
    found = _sun_and_moon(now, site)
    if found is not None:
        observed, geometric = found
        clock["sun_alt"] = round(observed[0], 2)
        clock["moon_alt"] = round(observed[1], 2)
        clock["twilight"] = twilight_phase(geometric[0])
    return clock
