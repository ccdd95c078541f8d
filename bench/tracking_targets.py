"""The targets of ``bench/tracking.py`` (issue #16): their data, written to files the way a user
gives them (``--elements``, ``--tle``), independent of the test suite's data.

- the comet C/2023 A3 (Tsuchinshan-ATLAS): its MPC one-line elements (MPEC 2024-K71);
- the ISS: the TLE of 2008-09-20 (Wikipedia's "Two-line element set" article), its elements
  moved to the run's date (``scopelink.astro.targets.placement.tle_moved_to``): a realistic
  orbit and pass on the simulators' clock.

Where a target is placed (the site under it, the high pass) is
``scopelink.astro.targets.placement``.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

from scopelink.astro.targets.placement import tle_moved_to

__all__ = ["COMET", "ISS", "write_comets", "write_iss_tle"]

COMET = "C/2023 A3"
COMET_ELEMENTS = (
    "    CK23A030  2024 09 27.7405  0.391424  1.000124  308.4916   21.5585  139.1103  20240526"
    "   5.0  4.0  C/2023 A3 (Tsuchinshan-ATLAS)                            MPEC 2024-K71"
)
"""MPC one-line format (CometEls.txt columns)."""

ISS = "ISS"
ISS_LINES = (
    "1 25544U 98067A   08264.51782528 -.00002182  00000-0 -11606-4 0  2927",
    "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537",
)


def write_comets(directory: Path) -> Path:
    """The comet's elements as a CometEls.txt-style file in ``directory``."""
    path = directory / "comets.txt"
    path.write_text(COMET_ELEMENTS + "\n", encoding="utf-8")
    return path


def write_iss_tle(epoch: datetime, directory: Path) -> Path:
    """The ISS's TLE with its elements at ``epoch`` (UTC) as a file in ``directory``."""
    path = directory / "iss.tle"
    path.write_text(tle_moved_to("ISS (ZARYA)", *ISS_LINES, epoch), encoding="utf-8")
    return path
