"""Helpers for the pointing-model tests and bench: a misaligned emulated sky, stars spread over
it, and the simulated observer who centres a star before a sync."""

from __future__ import annotations

import math
from datetime import datetime

from scopelink.astro import Site, angular_separation_deg, j2000_to_observed, observed_to_j2000
from scopelink.mount import AlignmentMode, Mount
from scopelink.sim import SimulatedMount
from scopelink.sim.misalignment import Misalignment

FIVE_DEGREES = Misalignment(
    zero_primary_deg=2.0, zero_secondary_deg=-1.5, polar_az_deg=3.0, polar_alt_deg=-2.5
)
"""Zero points of 2° and 1.5°, the polar axis 3° off in azimuth and 2.5° in altitude: about 5°
from the truth at worst."""


def stars(site: Site, when: datetime, count: int, *, offset: float) -> list[tuple[float, float]]:
    """``count`` J2000 positions spread over the sky between 25° and 75° altitude at ``when``
    (a golden-angle spiral; ``offset`` in [0, 1) picks another spiral)."""
    found = []
    for k in range(count):
        fraction = (k + offset) / count
        alt = 25.0 + 50.0 * fraction
        az = (137.508 * (k + 7.0 * offset)) % 360.0
        found.append(observed_to_j2000(alt, az, when, site))
    return found


def equatorial(sim: SimulatedMount) -> bool:
    return sim.model.alignment_mode is not AlignmentMode.ALT_AZ


def reading_for(sim: SimulatedMount, ra_hours: float, dec_deg: float) -> tuple[float, float]:
    """The J2000 position the simulator must read for its tube to point at this star now."""
    alt, az = j2000_to_observed(ra_hours, dec_deg, sim.now(), sim.site)
    raw = sim.misalignment.reading_of(alt, az, sim.site.latitude_deg, equatorial=equatorial(sim))
    return observed_to_j2000(*raw, sim.now(), sim.site)


def pointing_error_arcmin(sim: SimulatedMount, ra_hours: float, dec_deg: float) -> float:
    """How far (arcmin) the simulated tube truly points from this star now."""
    alt, az = j2000_to_observed(ra_hours, dec_deg, sim.now(), sim.site)
    true_alt, true_az = sim.true_pointing()
    return float(angular_separation_deg(az, alt, true_az, true_alt)) * 60.0


def rms(values: list[float]) -> float:
    return math.sqrt(sum(v * v for v in values) / len(values))


def settle(sim: SimulatedMount) -> None:
    """Step the simulated clock until the slew has landed."""
    for _ in range(200):
        if not sim.step(2.0).slewing:
            return
    raise AssertionError("the slew did not land")


async def centre(sim: SimulatedMount, ra_hours: float, dec_deg: float) -> None:
    """The observer centres the star in the eyepiece with the hand control's arrows (here: the
    simulator slews to where its tube points at the star; twice, so tracking cannot drift)."""
    for _ in range(2):
        await sim.goto_equatorial(*reading_for(sim, ra_hours, dec_deg))
        settle(sim)


async def goto_error_arcmin(
    mount: Mount, sim: SimulatedMount, ra_hours: float, dec_deg: float
) -> float:
    """Goto the star through ``mount`` (the driver) and return how far off the tube lands."""
    await mount.goto_equatorial(ra_hours, dec_deg)
    settle(sim)
    await mount.refresh()
    return pointing_error_arcmin(sim, ra_hours, dec_deg)


async def sync_on(mount: Mount, sim: SimulatedMount, ra_hours: float, dec_deg: float) -> None:
    """Centre the star, then sync on it through ``mount``."""
    await centre(sim, ra_hours, dec_deg)
    await mount.refresh()
    await mount.sync_equatorial(ra_hours, dec_deg)
