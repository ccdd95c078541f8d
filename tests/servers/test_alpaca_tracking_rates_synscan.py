"""Tracking rates through Alpaca in front of the SynScan driver and the real emulator (issue
#16): alpyca sets a lunar rate and custom RA/Dec rates, the driver's PC loop drives the hand
control, and the simulator behind the emulator is the truth; guide rates are set and a pulse
joins the loop."""

from __future__ import annotations

import asyncio
import math
from pathlib import Path

import pytest
from alpaca.exceptions import InvalidValueException
from alpaca.telescope import DriveRates, GuideDirections

from scopelink.astro import LUNAR_RATE_DEG_S, SIDEREAL_RATE_DEG_S, angular_separation_deg
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import TrackingMode
from scopelink.mount.rates import ra_rate_from_ascom
from scopelink.sim import SimClock, SimulatedMount
from tests.support.alpaca import blocking
from tests.support.rates import alpaca_telescope
from tests.support.synscan_driver import START, rig

SPEED_UP = 10.0


async def _rms_against_ideal(
    mount: SynScanMount, sim: SimulatedMount, ra_arcsec_s: float, dec_arcsec_s: float
) -> float:
    """RMS (arcsec) of the simulator's pointing against the loop's target over 60 s of the
    mount's time, the first 25 s left out as settling."""
    loop = mount.rate_loop_statistics
    assert loop is not None
    assert loop.started_at is not None
    assert loop.anchor is not None
    t0 = (loop.started_at - sim.clock.epoch).total_seconds()
    ra0, dec0 = loop.anchor
    errors: list[float] = []
    for step in range(30):
        await asyncio.sleep(0.2)
        if step < 12:
            continue
        t = sim.elapsed()
        ra, dec = sim.j2000_at(t)
        ideal_ra = ra0 + ra_arcsec_s * (t - t0) / 54000.0
        ideal_dec = dec0 + dec_arcsec_s * (t - t0) / 3600.0
        errors.append(3600.0 * angular_separation_deg(ideal_ra * 15.0, ideal_dec, ra * 15.0, dec))
    return math.sqrt(sum(e * e for e in errors) / len(errors))


@pytest.mark.solo
async def test_lunar_and_custom_rates_through_alpaca_on_synscan(tmp_path: Path) -> None:
    async with rig("tcp", clock=SimClock.accelerated(SPEED_UP, START)) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with alpaca_telescope(r.mount, tmp_path) as telescope:
            rates = await blocking(lambda: list(telescope.TrackingRates))
            assert DriveRates.driveLunar in rates
            assert DriveRates.driveKing in rates
            assert await blocking(lambda: telescope.CanSetRightAscensionRate) is True

            await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveLunar))
            await blocking(lambda: setattr(telescope, "Tracking", True))
            assert await blocking(lambda: telescope.Tracking) is True
            assert r.mount.state.tracking is TrackingMode.LUNAR
            lunar = (SIDEREAL_RATE_DEG_S - LUNAR_RATE_DEG_S) * 3600.0
            lunar_rms = await _rms_against_ideal(r.mount, r.sim, lunar, 0.0)

            await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveSidereal))
            await blocking(lambda: setattr(telescope, "RightAscensionRate", 1.5))
            await blocking(lambda: setattr(telescope, "DeclinationRate", 12.0))
            assert await blocking(lambda: telescope.Tracking) is True
            custom_rms = await _rms_against_ideal(r.mount, r.sim, ra_rate_from_ascom(1.5), 12.0)
            print(
                f"Alpaca on SynScan: lunar {lunar_rms:.2f}″ RMS, custom (1.5 s/sidereal s, "
                f"12″/s) {custom_rms:.2f}″ RMS after settling"
            )
            assert lunar_rms < 5.0, f"lunar rate {lunar_rms:.2f}″ RMS against the ideal"
            assert custom_rms < 5.0, f"custom rates {custom_rms:.2f}″ RMS against the ideal"

            # Guide rates: stored on the driver, used by PulseGuide, which joins the loop.
            assert await blocking(lambda: telescope.CanSetGuideRates) is True
            await blocking(lambda: setattr(telescope, "GuideRateDeclination", 0.003))
            assert r.mount.guide_rates_deg_s == (r.mount.guide_rate_deg_s, 0.003)
            assert await blocking(lambda: telescope.GuideRateDeclination) == 0.003
            with pytest.raises(InvalidValueException, match="10x sidereal"):
                await blocking(lambda: setattr(telescope, "GuideRateRightAscension", 1.0))
            assert r.mount.guide_rates_deg_s[1] == 0.003  # nothing changed
            await blocking(lambda: telescope.PulseGuide(GuideDirections.guideSouth, 200))
            await r.mount.wait_for(lambda s: not s.pulse_guiding, 5.0)
            assert r.mount.custom_rates_running, "the pulse ended the loop"
            loop = r.mount.rate_loop_statistics
            assert loop is not None
            assert loop.pulses == 1

            await blocking(lambda: setattr(telescope, "Tracking", False))
            assert r.sim.tracking is TrackingMode.OFF
            assert not r.mount.custom_rates_running
