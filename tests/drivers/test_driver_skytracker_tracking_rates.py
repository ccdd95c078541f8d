"""Custom tracking rates on the Sky Tracker driver: timed guide presses in a closed loop (issue
#16), against the real emulator over TCP, with the simulator behind it as the truth."""

from __future__ import annotations

import asyncio
import math
from pathlib import Path

import pytest

from scopelink.drivers.skytracker import SkyTrackerMount
from scopelink.mount import GuideDirection, TrackingMode
from scopelink.protocol.skytracker import TrackerMode
from tests.support.rates import loop_anchor
from tests.support.skytracker_driver import Rig, box_mode, eventually, rig, separation_deg

SPEED_UP = 10.0
"""Simulated seconds per real second: the presses are timed on the PC (1 s periods), so the
ripple of the timed presses grows with the speed-up."""


def _running(mount: SkyTrackerMount) -> bool:
    """Whether the PC loop runs (a call, so mypy does not narrow it across awaits)."""
    return mount.custom_rates_running


def _tracking(mount: SkyTrackerMount) -> TrackingMode:
    return mount.state.tracking


async def _track_at(r: Rig, alt_deg: float, az_deg: float) -> None:
    r.point(alt_deg, az_deg)
    await r.driver.set_tracking(TrackingMode.ALT_AZ)
    await eventually(lambda: all(axis.rate != 0.0 for axis in r.sim.axes))


@pytest.mark.solo
async def test_custom_rates_follow_the_integrated_target(tmp_path: Path) -> None:
    async with rig(tmp_path, "tcp", clock_rate=SPEED_UP, guide_speed_arcsec_s=20) as r:
        await _track_at(r, 45.0, 120.0)
        ra_rate, dec_rate = 20.0, -6.0  # arcsec/s of RA and Dec: a fast comet
        async with r.driver.watching():
            await r.driver.set_tracking_rates(ra_rate, dec_rate)
            loop, t0, ra0, dec0 = loop_anchor(r.driver.rate_loop_statistics, r.sim.clock.epoch)
            assert _running(r.driver)
            errors: list[float] = []
            for _ in range(32):  # 6.4 s of real time, 64 s of the mount's
                await asyncio.sleep(0.2)
                t = r.sim.elapsed()
                ideal = (ra0 + ra_rate * (t - t0) / 54000.0, dec0 + dec_rate * (t - t0) / 3600.0)
                errors.append(3600.0 * separation_deg(r.sim.j2000_at(t), ideal))
                assert not r.driver.state.slewing  # the loop's presses are tracking
            assert r.driver.state.tracking is TrackingMode.ALT_AZ
            assert box_mode(r) in (TrackerMode.GUIDE, TrackerMode.TRACK)
        settled = errors[12:]  # after 2.4 s real (24 s, 2.4 loop time constants)
        rms = math.sqrt(sum(e * e for e in settled) / len(settled))
        print(
            f"Sky Tracker custom rates ({ra_rate}, {dec_rate})″/s: truth RMS {rms:.1f}″ after "
            f"settling, max {max(settled):.1f}″, {len(loop.errors_arcsec)} readings used, "
            f"{loop.commands} press commands, {r.driver.line.statistics.commands_sent} commands "
            f"in all"
        )
        assert rms <= 30.0, f"RMS {rms:.1f}″ against the integrated target (errors {settled})"
        # A guide pulse joins the loop: up at the pulse speed (20″/s) for 1 s of the PC's time,
        # and the loop keeps it (its target moves along) instead of undoing it.
        async with r.driver.watching():
            alt_before = r.sim.observed_at(r.sim.elapsed())[0]
            mount_start, real_start = r.sim.elapsed(), asyncio.get_running_loop().time()
            await r.driver.pulse_guide(GuideDirection.NORTH, 1000)
            assert r.driver.state.pulse_guiding
            await r.driver.wait_for(lambda s: not s.pulse_guiding, 5.0)
            ratio = (r.sim.elapsed() - mount_start) / (
                asyncio.get_running_loop().time() - real_start
            )
            await asyncio.sleep(1.5)  # 15 s of the mount's: it would have undone the pulse
            assert _running(r.driver), "the pulse ended the loop"
            offsets = []
            for _ in range(5):  # the mean over half a second: less of the presses' ripple
                await asyncio.sleep(0.1)
                t = r.sim.elapsed()
                ideal = (ra0 + ra_rate * (t - t0) / 54000.0, dec0 + dec_rate * (t - t0) / 3600.0)
                offsets.append(3600.0 * separation_deg(r.sim.j2000_at(t), ideal))
            offset = sum(offsets) / len(offsets)
        expected = 20.0 * ratio
        print(
            f"pulse north 1000 ms in the loop: {offset:.0f}″ off the unpulsed target "
            f"(pulse speed x time {expected:.0f}″)"
        )
        assert loop.pulses == 1
        # Kept, not undone (the loop would have pulled it back to 45″ by now): 193-200″ in runs.
        assert abs(offset - expected) <= 40.0  # the loop's own error is within ±30″
        assert r.sim.observed_at(r.sim.elapsed())[0] != alt_before
        # Back to zero: the box tracks by itself again, nothing pressed.
        await r.driver.set_tracking_rates(0.0, 0.0)
        assert not _running(r.driver)
        assert r.emulator.tracker.remote_pressed == 0
        assert box_mode(r) is TrackerMode.TRACK
        assert not r.driver.guard.rate_motions
