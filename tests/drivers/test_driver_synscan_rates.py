"""Custom tracking rates on the SynScan driver: the PC loop of rate slews (issue #16), against
the real emulator over TCP, with the simulator behind it as the truth."""

from __future__ import annotations

import asyncio
import math

import pytest

from scopelink.astro import angular_separation_deg
from scopelink.drivers.synscan import SynScanMount
from scopelink.drivers.synscan.rates import RateLoopStatistics
from scopelink.mount import GuideDirection, TrackingMode
from scopelink.protocol.synscan import FixedRateSlew, SetTrackingMode
from scopelink.sim import SimClock
from tests.support.rates import loop_anchor
from tests.support.synscan_driver import START, Rig, record_commands, rig

SPEED_UP = 10.0
"""Simulated seconds per real second (the emulator's simulator costs CPU per rate command)."""


def _running(mount: SynScanMount) -> bool:
    """Whether the PC loop runs (a call, so mypy does not narrow it across awaits)."""
    return mount.custom_rates_running


def _truth_error_arcsec(
    sim_j2000: tuple[float, float],
    start: tuple[float, float, float],
    t: float,
    ra_arcsec_s: float,
    dec_arcsec_s: float,
) -> float:
    dt = t - start[0]
    ideal_ra = start[1] + ra_arcsec_s * dt / 54000.0
    ideal_dec = start[2] + dec_arcsec_s * dt / 3600.0
    ra, dec = sim_j2000
    return 3600.0 * angular_separation_deg(ideal_ra * 15.0, ideal_dec, ra * 15.0, dec)


UPDATES = [(32.0, -6.0), (28.0, -10.0), (33.0, -7.0), (30.0, -9.0), (31.0, -8.0)]
"""A rate update every 0.3 s of real time (3 s of the mount's): a satellite's every second at
3x the pace."""


async def _rate_updates_change_the_running_loop(
    r: Rig, first: tuple[float, float, float, float, float]
) -> None:
    """A new rate while the loop runs: no axis stop, no tracking hand-back, the target going on
    from where it was (issue #16: at a satellite's 1 s updates the restarts lost ground).
    ``first``: the loop's start (mount seconds, RA h, Dec °) and its rates."""
    commands = record_commands(r.emulator)
    pieces = [first]  # the ideal, integrated piecewise from each update's time on

    def ideal(t: float) -> tuple[float, float]:
        start, ra, dec, ra_rate, dec_rate = next(p for p in reversed(pieces) if p[0] <= t)
        return ra + ra_rate * (t - start) / 54000.0, dec + dec_rate * (t - start) / 3600.0

    errors: list[float] = []
    for ra_rate, dec_rate in UPDATES:
        t = r.sim.elapsed()
        pieces.append((t, *ideal(t), ra_rate, dec_rate))
        await r.mount.set_tracking_rates(ra_rate, dec_rate)
        for _ in range(6):
            await asyncio.sleep(0.05)
            t = r.sim.elapsed()
            (ra, dec), (ideal_ra, ideal_dec) = r.sim.j2000_at(t), ideal(t)
            errors.append(3600.0 * angular_separation_deg(ideal_ra * 15, ideal_dec, ra * 15, dec))
    assert _running(r.mount)
    stops = [c for c in commands if isinstance(c, FixedRateSlew) and c.rate == 0]
    hand_backs = [c for c in commands if isinstance(c, SetTrackingMode)]
    print(
        f"{len(UPDATES)} rate updates: truth max {max(errors):.2f}″ across them, "
        f"{r.mount.rate_updates} taken by the running loop, {len(commands)} commands"
    )
    assert not stops, f"an axis was stopped between updates: {stops}"
    assert not hand_backs, f"tracking was handed back between updates: {hand_backs}"
    assert r.mount.rate_updates == len(UPDATES)
    assert max(errors) < 5.0, f"off the integrated target across an update ({errors})"


@pytest.mark.solo
async def test_custom_rates_follow_the_integrated_target_and_take_updates_in_place() -> None:
    async with rig("tcp", clock=SimClock.accelerated(SPEED_UP, START)) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        await r.mount.wait_for_slew(timeout_s=15.0)
        ra_rate, dec_rate = 30.0, -8.0  # arcsec/s: a fast comet
        async with r.mount.watching():
            await r.mount.set_tracking_rates(ra_rate, dec_rate)
            # The target: integrated from where the loop read the mount when it started.
            _, t0, ra0, dec0 = loop_anchor(r.mount.rate_loop_statistics, r.sim.clock.epoch)
            assert _running(r.mount)
            assert r.mount.state.tracking is TrackingMode.SIDEREAL  # ours, though 't' reads off
            errors: list[float] = []
            for _ in range(40):  # 8 s of real time, 80 s of the mount's
                await asyncio.sleep(0.2)
                t = r.sim.elapsed()
                errors.append(
                    _truth_error_arcsec(r.sim.j2000_at(t), (t0, ra0, dec0), t, ra_rate, dec_rate)
                )
            assert r.mount.state.tracking is TrackingMode.SIDEREAL
        settled = errors[15:]  # after 3 s real (30 s, six loop time constants)
        rms = math.sqrt(sum(e * e for e in settled) / len(settled))
        stats = r.mount.rate_loop_statistics
        assert isinstance(stats, RateLoopStatistics)
        print(
            f"SynScan custom rates ({ra_rate}, {dec_rate})″/s: truth RMS {rms:.2f}″ after "
            f"settling, max {max(settled):.2f}″, {len(stats.errors_arcsec)} polls, "
            f"{stats.commands} rate commands"
        )
        assert rms < 5.0, f"RMS {rms:.2f}″ against the integrated target (errors {settled})"
        async with r.mount.watching():
            await _rate_updates_change_the_running_loop(r, (t0, ra0, dec0, ra_rate, dec_rate))
        # Back to zero: the hand control tracks by itself again.
        await r.mount.set_tracking_rates(0.0, 0.0)
        assert not _running(r.mount)
        assert r.sim.tracking is TrackingMode.SIDEREAL
        assert not r.mount.guard.rate_motions


async def test_a_guide_pulse_joins_the_loop_and_an_abort_ends_it() -> None:
    async with rig("tcp", clock=SimClock.accelerated(SPEED_UP, START)) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with r.mount.watching():
            await r.mount.set_tracking_rates(15.0, 0.0)
            loop, t0, ra0, dec0 = loop_anchor(r.mount.rate_loop_statistics, r.sim.clock.epoch)
            await asyncio.sleep(0.5)
            real_start = asyncio.get_running_loop().time()
            mount_start = r.sim.elapsed()
            await r.mount.pulse_guide(GuideDirection.NORTH, 1000)
            assert r.mount.state.pulse_guiding
            await r.mount.wait_for(lambda s: not s.pulse_guiding, 5.0)
            ratio = (r.sim.elapsed() - mount_start) / (
                asyncio.get_running_loop().time() - real_start
            )
            await asyncio.sleep(1.5)  # three loop time constants: it would have undone the pulse
            assert _running(r.mount), "the pulse ended the loop"
            t = r.sim.elapsed()
            ra, dec = r.sim.j2000_at(t)
            expected = r.mount.guide_rate_deg_s * 3600.0 * ratio  # arcsec: 1 s of the PC's time
            shift = (dec - dec0) * 3600.0
            drift = (ra - (ra0 + 15.0 * (t - t0) / 54000.0)) * 54000.0
            print(
                f"pulse north 1000 ms: Dec moved {shift:.1f}″ (guide rate x time {expected:.1f}″)"
            )
            assert shift == pytest.approx(expected, abs=0.15 * expected + 3.0)
            assert abs(drift) < 5.0  # RA still follows its rate
            assert loop.pulses == 1
            await r.mount.abort()
            await r.mount.wait_for(lambda s: not r.mount.custom_rates_running, 5.0)
        assert r.sim.tracking is TrackingMode.SIDEREAL
        assert not r.mount.guard.rate_motions


async def test_a_client_that_leaves_takes_its_rates_with_it() -> None:
    async with rig("tcp", clock=SimClock.accelerated(SPEED_UP, START)) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with r.mount.watching(), r.mount.motion_client("phone"):
            await r.mount.set_tracking_rates(10.0, 10.0)
            assert _running(r.mount)
            await r.mount.set_tracking_rates(12.0, 8.0)  # the running loop takes it: still its
            assert r.mount.rate_updates == 1
        assert not _running(r.mount)
        assert r.mount.tracking_rates.zero
        assert r.sim.tracking is TrackingMode.SIDEREAL
        assert not r.mount.guard.rate_motions


async def test_a_goto_ends_the_loop_and_is_never_overridden() -> None:
    async with rig("tcp", clock=SimClock.accelerated(SPEED_UP, START)) as r:
        await r.mount.goto_equatorial(7.5, 35.0)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with r.mount.watching():
            await r.mount.set_tracking_rates(20.0, 5.0)
            assert _running(r.mount)
            await r.mount.goto_equatorial(8.0, 30.0)  # the loop gives way to the goto
            await r.mount.set_tracking_rates(20.0, 5.0)  # during the goto: not started
            await r.mount.wait_for_slew(timeout_s=15.0)
            assert not _running(r.mount)
            state = await r.mount.refresh()
        assert state.ra_j2000_hours == pytest.approx(8.0, abs=0.01)  # the goto landed
        assert state.dec_j2000_deg == pytest.approx(30.0, abs=0.05)
        assert r.sim.tracking is TrackingMode.SIDEREAL
        assert not r.mount.guard.rate_motions
