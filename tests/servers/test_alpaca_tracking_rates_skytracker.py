"""Tracking and guide rates through Alpaca in front of the Sky Tracker driver and the real
emulator (issue #16): alpyca sees lunar, solar and King rates and settable RA/Dec and guide
rates; lunar tracking is the driver's loop of timed presses, a pulse joins it, a client that
leaves takes its rates along, and a GOTO ends the loop with nothing left pressed."""

from __future__ import annotations

from pathlib import Path

import pytest
from alpaca.exceptions import InvalidValueException
from alpaca.telescope import DriveRates, GuideDirections

from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.mount import TrackingMode
from scopelink.protocol.skytracker import TrackerMode
from tests.support.alpaca import blocking
from tests.support.rates import alpaca_telescope
from tests.support.skytracker_driver import box_mode, eventually, rig


def _running(mount: SkyTrackerMount) -> bool:
    return mount.custom_rates_running


def _tracking(mount: SkyTrackerMount) -> TrackingMode:
    return mount.state.tracking


async def test_rates_and_guide_rates_through_alpaca_on_the_sky_tracker(tmp_path: Path) -> None:
    async with rig(tmp_path, "tcp") as r:
        r.point(40.0, 200.0)
        async with alpaca_telescope(r.driver, tmp_path) as telescope:
            rates = await blocking(lambda: list(telescope.TrackingRates))
            assert set(rates) == {
                DriveRates.driveSidereal,
                DriveRates.driveLunar,
                DriveRates.driveSolar,
                DriveRates.driveKing,
            }
            assert await blocking(lambda: telescope.CanSetRightAscensionRate) is True
            assert await blocking(lambda: telescope.CanSetDeclinationRate) is True
            assert await blocking(lambda: telescope.CanSetGuideRates) is True

            # Guide rates: the box's K speeds, azimuth for RA, elevation for Dec.
            await blocking(lambda: setattr(telescope, "GuideRateDeclination", 20.0 / 3600.0))
            assert r.emulator.tracker.guide_speeds_arcsec_s == (120, 20)
            assert await blocking(lambda: telescope.GuideRateRightAscension) == pytest.approx(
                120.0 / 3600.0
            )
            with pytest.raises(InvalidValueException, match="1-255"):
                await blocking(lambda: setattr(telescope, "GuideRateRightAscension", 1.0))
            assert r.emulator.tracker.guide_speeds_arcsec_s == (120, 20)  # nothing changed

            await blocking(lambda: setattr(telescope, "TrackingRate", DriveRates.driveLunar))
            await blocking(lambda: setattr(telescope, "Tracking", True))
            assert _running(r.driver)  # lunar: sidereal (the box) + 0.356″/s of RA (the loop)
            assert _tracking(r.driver) is TrackingMode.LUNAR
            assert await blocking(lambda: telescope.TrackingRate) == DriveRates.driveLunar
            async with r.driver.motion_client("phone"):
                await r.driver.set_tracking_rates(10.0, 5.0)
                assert _running(r.driver)
            # The client left: its rates went back to zero; lunar tracking goes on.
            assert r.driver.tracking_rates.zero
            assert _running(r.driver)
            await blocking(lambda: telescope.PulseGuide(GuideDirections.guideNorth, 300))
            await eventually(lambda: not r.driver.state.pulse_guiding)
            assert _running(r.driver), "the pulse ended the loop"
            loop = r.driver.rate_loop_statistics
            assert loop is not None
            assert loop.pulses == 1
            assert await blocking(lambda: telescope.Slewing) is False

            target = r.sim_j2000()
            await r.driver.goto_equatorial(target[0] + 0.2, target[1])  # ends the loop
            assert not _running(r.driver)
            await r.driver.wait_for_slew(timeout_s=15.0)
            await r.driver.refresh()
        # Nothing the loop pressed survives the GOTO: the box tracks by itself.
        assert r.emulator.tracker.remote_pressed == 0
        assert box_mode(r) is TrackerMode.TRACK
        assert _tracking(r.driver) is TrackingMode.SIDEREAL
        assert not r.driver.guard.rate_motions
