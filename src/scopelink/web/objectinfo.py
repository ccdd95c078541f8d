"""What the page shows about a selected object (``GET /api/object?name=``): type, magnitude, size,
constellation, where it is now, rise/transit/set, and when it reaches one of the mount's limits.

All times are the mount's (a simulator may run a faster clock) and cover the next 24 hours:

- ``rise``/``transit``/``set``: the almanac's (:func:`scopelink.astro.catalog.rise_transit_set`,
  the standard horizon), with ``always_up``/``never_up`` for circumpolar or never-rising objects;
- ``limit``: the first time the object crosses the mount's own horizon limit (its profile by
  azimuth included), sampled every 5 minutes, ``"sets"`` below it or ``"rises"`` above it;
- ``meridian``: on a German mount, when a tube following the object on the west side of the pier
  (before the meridian) reaches ``limits.meridian_west_deg`` past the meridian.

Size comes from OpenNGC (major and minor axis, arcminutes) for NGC and IC objects; other objects
have none.
"""

from __future__ import annotations

import re
import sqlite3
from datetime import datetime, timedelta
from functools import cache

import numpy as np
import pyongc

from scopelink.astro import j2000_to_observed
from scopelink.astro.catalog import find, rise_transit_set
from scopelink.astro.catalog.entries import CatalogEntry
from scopelink.astro.timescales import utc_pair
from scopelink.mount import Mount
from scopelink.mount.meridian import TRACKING_DEG_PER_MIN, applies, hour_angle_of_j2000

__all__ = ["LIMIT_STEP_MIN", "object_info", "size_arcmin"]

LIMIT_STEP_MIN = 5
"""Sampling of the crossing of the mount's horizon limit (minutes)."""
_WINDOW_H = 24
_NGC_IC = re.compile(r"^(NGC|IC) (\d+)(.*)$")


@cache
def _sizes() -> dict[str, tuple[float | None, float | None]]:
    connection = sqlite3.connect(f"file:{pyongc.DBPATH}?mode=ro", uri=True)
    try:
        rows = connection.execute("SELECT name, majax, minax FROM objects").fetchall()
    finally:
        connection.close()
    return {name: (major, minor) for name, major, minor in rows if major is not None}


def size_arcmin(entry: CatalogEntry) -> tuple[float | None, float | None] | None:
    """OpenNGC's major and minor axis (arcminutes) of an NGC or IC object, else None."""
    for name in (entry.name, *entry.aliases):
        match = _NGC_IC.match(name)
        if match:
            prefix, number, rest = match.groups()
            found = _sizes().get(f"{prefix}{int(number):04d}{rest}")
            if found is not None:
                return found
    return None


def _iso(t: datetime | None) -> str | None:
    return None if t is None else t.isoformat()


def _horizon_crossing(mount: Mount, entry: CatalogEntry, now: datetime) -> dict[str, object] | None:
    """The first crossing of the mount's horizon limit within the window."""
    steps = np.arange(0, _WINDOW_H * 60 + LIMIT_STEP_MIN, LIMIT_STEP_MIN)
    jd1, jd2 = (float(part) for part in utc_pair(now))
    times = (np.full(steps.shape, jd1), jd2 + steps / 1440.0)
    site, limits = mount.site, mount.limits
    ra, dec, _ = entry.position.astrometric(times, site)
    alt, az = j2000_to_observed(ra, dec, times, site)
    alts = np.atleast_1d(alt)
    allowed = np.array([limits.horizon_at(float(a)) for a in np.atleast_1d(az)])
    above = alts >= allowed
    changes = np.flatnonzero(above[1:] != above[:-1])
    if changes.size == 0:
        return None
    index = int(changes[0]) + 1
    at = now + timedelta(minutes=int(steps[index]))
    return {"at": at.isoformat(), "event": "rises" if above[index] else "sets"}


def _meridian_limit(mount: Mount, ra: float, dec: float, now: datetime) -> str | None:
    if not applies(mount.capabilities):
        return None
    ha_hours, _ = hour_angle_of_j2000(mount, ra, dec)
    past = 15.0 * ha_hours  # degrees west of the meridian (ha in [-12, 12))
    to_go = mount.limits.meridian_west_deg - past
    if to_go < 0.0:
        to_go += 360.0  # past it now: the next time round
    return (now + timedelta(minutes=to_go / TRACKING_DEG_PER_MIN)).isoformat()


def object_info(mount: Mount, name: str) -> dict[str, object]:
    """Everything the information panel shows about ``name`` (unknown names raise
    :class:`~scopelink.astro.catalog.UnknownObjectError`)."""
    entry = find(name)
    now, site = mount.now(), mount.site
    ra_now, dec_now, _ = entry.position.astrometric(now, site)
    ra, dec = float(ra_now), float(dec_now)
    alt, az = j2000_to_observed(ra, dec, now, site)
    size = size_arcmin(entry)
    events = rise_transit_set(entry, site, now, window_hours=_WINDOW_H)
    return {
        "name": entry.name,
        "kind": entry.kind.value,
        "type": entry.type_description,
        "magnitude": entry.magnitude,
        "constellation": entry.constellation,
        "size_arcmin": None if size is None else list(size),
        "ra_j2000_hours": round(ra, 6),
        "dec_j2000_deg": round(dec, 5),
        "alt_deg": round(alt, 3),
        "az_deg": round(az, 3),
        "rise": _iso(events.rise),
        "transit": _iso(events.transit),
        "set": _iso(events.set),
        "always_up": events.always_up,
        "never_up": events.never_up,
        "limit": _horizon_crossing(mount, entry, now),
        "meridian_limit": _meridian_limit(mount, ra, dec, now),
        "now": now.isoformat(),
    }
