"""Moving-target helpers for the tracking tests and bench/tracking.py: test data files, a TLE
moved to a chosen epoch, and a site where a place culminates high at a given time."""

from __future__ import annotations

from datetime import datetime, timedelta
from pathlib import Path

from scopelink.astro import Site, gmst_hours
from scopelink.astro.targets import SatellitePass, SatelliteTarget, next_pass

DATA = Path(__file__).resolve().parent.parent / "data"
COMETS = DATA / "comets.txt"
SATELLITES = DATA / "satellites.tle"

ISS_LINE1 = "1 25544U 98067A   08264.51782528 -.00002182  00000-0 -11606-4 0  2927"
ISS_LINE2 = "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537"
"""The ISS on 2008-09-20 (the TLE of Wikipedia's "Two-line element set" article)."""


def _with_checksum(line: str) -> str:
    total = sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68])
    return line[:68] + str(total % 10)


def iss_tle_at(epoch: datetime, path: Path) -> Path:
    """A three-line TLE file with the ISS's 2008 elements at ``epoch`` (UTC): a realistic ISS
    orbit that SGP4 propagates near any date (the simulators run on today's clock)."""
    start = datetime(epoch.year, 1, 1, tzinfo=epoch.tzinfo)
    day = 1.0 + (epoch - start).total_seconds() / 86400.0
    line1 = f"{ISS_LINE1[:18]}{epoch.year % 100:02d}{day:012.8f}{ISS_LINE1[32:]}"
    path.write_text(f"ISS (ZARYA)\n{_with_checksum(line1)}\n{ISS_LINE2}\n", encoding="utf-8")
    return path


def site_under(ra_hours: float, dec_deg: float, t: datetime) -> Site:
    """A site where the J2000 place (RA, Dec) is near the meridian at ``t``, ~30° from the
    zenith towards the equator (well above any horizon, away from the pole)."""
    longitude = ((ra_hours - gmst_hours(t)) * 15.0 + 180.0) % 360.0 - 180.0
    latitude = max(-60.0, min(60.0, dec_deg + (30.0 if dec_deg >= 0 else -30.0)))
    return Site(latitude, longitude)


def high_pass(target: SatelliteTarget, start: datetime, min_alt_deg: float = 30.0) -> SatellitePass:
    """The first pass after ``start`` culminating at least ``min_alt_deg`` high."""
    t = start
    for _ in range(200):
        found = next_pass(target, t)
        if found is None:
            break
        if found.max_alt_deg >= min_alt_deg:
            return found
        t = found.set + timedelta(minutes=1)
    raise AssertionError(f"no pass of {target.name} above {min_alt_deg}° after {start}")
