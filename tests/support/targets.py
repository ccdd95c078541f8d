"""Moving-target helpers for the tracking tests: test data files and a TLE moved to a chosen
epoch. Placing a scene (a site under a target, a high pass) is
``scopelink.astro.targets.placement``, shared with ``bench/tracking.py``."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

from scopelink.astro.targets.placement import high_pass, site_under, tle_moved_to

__all__ = ["COMETS", "DATA", "SATELLITES", "high_pass", "iss_tle_at", "site_under"]

DATA = Path(__file__).resolve().parent.parent / "data"
COMETS = DATA / "comets.txt"
SATELLITES = DATA / "satellites.tle"

ISS_LINE1 = "1 25544U 98067A   08264.51782528 -.00002182  00000-0 -11606-4 0  2927"
ISS_LINE2 = "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537"
"""The ISS on 2008-09-20 (the TLE of Wikipedia's "Two-line element set" article)."""


def iss_tle_at(epoch: datetime, path: Path) -> Path:
    """A three-line TLE file with the ISS's 2008 elements at ``epoch`` (UTC)."""
    path.write_text(tle_moved_to("ISS (ZARYA)", ISS_LINE1, ISS_LINE2, epoch), encoding="utf-8")
    return path
