"""Where and when a moving target is well placed, for simulations, demonstrations and
benchmarks: a site under a J2000 place at an instant, a TLE's elements moved to another epoch,
and the first satellite pass culminating high.

Nothing here is used to point a telescope: these set up a scene (``bench/tracking.py`` and the
tests put the simulators' site and clock where a target is high).
"""

from __future__ import annotations

from datetime import datetime, timedelta

from scopelink.astro.sidereal import gmst_hours
from scopelink.astro.site import Site
from scopelink.astro.targets.base import TargetError
from scopelink.astro.targets.passes import SatellitePass, next_pass
from scopelink.astro.targets.satellite import SatelliteTarget

__all__ = ["PASSES_SEARCHED", "high_pass", "site_under", "tle_moved_to"]

PASSES_SEARCHED = 200
"""``high_pass`` looks at this many passes at most (a few weeks of a low satellite's)."""


def site_under(ra_hours: float, dec_deg: float, t: datetime) -> Site:
    """A site where the J2000 place (RA, Dec) is near the meridian at ``t``, ~30° from the
    zenith towards the equator (well above any horizon, away from the pole)."""
    longitude = ((ra_hours - gmst_hours(t)) * 15.0 + 180.0) % 360.0 - 180.0
    latitude = max(-60.0, min(60.0, dec_deg + (30.0 if dec_deg >= 0 else -30.0)))
    return Site(latitude, longitude)


def _with_checksum(line: str) -> str:
    total = sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68])
    return line[:68] + str(total % 10)


def tle_moved_to(name: str, line1: str, line2: str, epoch: datetime) -> str:
    """A three-line TLE (text) with the elements of ``line1``/``line2`` at ``epoch`` (UTC): a
    realistic orbit that SGP4 propagates near any date (a simulator runs on any clock)."""
    start = datetime(epoch.year, 1, 1, tzinfo=epoch.tzinfo)
    day = 1.0 + (epoch - start).total_seconds() / 86400.0
    moved = f"{line1[:18]}{epoch.year % 100:02d}{day:012.8f}{line1[32:]}"
    return f"{name}\n{_with_checksum(moved)}\n{line2}\n"


def high_pass(target: SatelliteTarget, start: datetime, min_alt_deg: float = 30.0) -> SatellitePass:
    """The first pass after ``start`` culminating at least ``min_alt_deg`` high (TargetError
    when none is among the next :data:`PASSES_SEARCHED`)."""
    t = start
    for _ in range(PASSES_SEARCHED):
        found = next_pass(target, t)
        if found is None:
            break
        if found.max_alt_deg >= min_alt_deg:
            return found
        t = found.set + timedelta(minutes=1)
    raise TargetError(f"no pass of {target.name} culminates above {min_alt_deg}° after {start}")
