"""Custom tracking rates on an alt-az SynScan mount (AZ GTi): the PC loop on the azimuth and
altitude axes (issue #16), against the real emulator in alt-az mode over TCP, the simulator
behind it as the truth."""

from __future__ import annotations

import asyncio
import math

from scopelink.astro import angular_separation_deg, observed_to_j2000
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import TrackingMode
from scopelink.protocol.synscan import (
    Axis,
    FixedRateSlew,
    SetTrackingMode,
    Tracking,
    VariableRateSlew,
)
from scopelink.servers.synscan import SynScanConfig
from scopelink.sim import AZ_GTI, SimClock, SimulatedMount
from tests.support.rates import loop_anchor
from tests.support.synscan_driver import START, record_commands, rig

SPEED_UP = 20.0
"""Simulated seconds per real second (the Moon-like rates are slow: the reading lag is small)."""
MOON_LIKE = (0.6, 0.2)
"""Arcsec of RA and of Dec per second: the Moon's motion against the stars, roughly."""


def _running(mount: SynScanMount) -> bool:
    return mount.custom_rates_running


def _hand_control_tracking(sim: SimulatedMount) -> TrackingMode:
    """The emulated mount's tracking (a call, so mypy does not narrow it across awaits)."""
    return sim.tracking


async def test_the_altaz_loop_follows_and_a_goto_or_an_abort_hands_tracking_back() -> None:
    async with rig(
        "tcp",
        model=AZ_GTI,
        config=SynScanConfig(model=165),
        clock=SimClock.accelerated(SPEED_UP, START),
    ) as r:
        caps = r.mount.capabilities
        assert caps.max_tracking_offset_arcsec_s > 0.0
        assert TrackingMode.SIDEREAL in caps.tracking_modes  # the follower's: alt-az tracking
        ra, dec = observed_to_j2000(50.0, 120.0, r.mount.now(), r.mount.site)
        await r.mount.goto_equatorial(ra, dec)
        await r.mount.wait_for_slew(timeout_s=15.0)
        async with r.mount.watching():
            commands = record_commands(r.emulator)
            await r.mount.set_tracking_rates(*MOON_LIKE)
            assert _running(r.mount)
            assert r.mount.state.tracking is TrackingMode.ALT_AZ  # ours, though 't' reads off
            assert _hand_control_tracking(r.sim) is TrackingMode.OFF  # the PC drives the axes
            slews = [c for c in commands if isinstance(c, VariableRateSlew)]
            assert {c.axis for c in slews} == {Axis.AZM_RA, Axis.ALT_DEC}  # both axes driven
            _, t0, ra0, dec0 = loop_anchor(r.mount.rate_loop_statistics, r.sim.clock.epoch)
            errors: list[float] = []
            for _ in range(20):  # 4 s of real time, 80 s of the mount's
                await asyncio.sleep(0.2)
                t = r.sim.elapsed()
                ideal_ra = ra0 + MOON_LIKE[0] * (t - t0) / 54000.0
                ideal_dec = dec0 + MOON_LIKE[1] * (t - t0) / 3600.0
                sim_ra, sim_dec = r.sim.j2000_at(t)
                errors.append(
                    3600.0 * angular_separation_deg(ideal_ra * 15, ideal_dec, sim_ra * 15, sim_dec)
                )
            settled = errors[6:]  # after 24 s of the mount's (five time constants)
            rms = math.sqrt(sum(e * e for e in settled) / len(settled))
            stats = r.mount.rate_loop_statistics
            assert stats is not None
            print(
                f"alt-az loop at {MOON_LIKE}″/s: truth RMS {rms:.2f}″, max {max(settled):.2f}″, "
                f"{len(stats.errors_arcsec)} polls, {stats.commands} rate commands"
            )
            assert rms <= 10.0, f"RMS {rms:.2f}″ against the integrated target ({settled})"
            # A goto ends the loop: the goto lands, the hand control tracks by itself again.
            ra2, dec2 = observed_to_j2000(45.0, 140.0, r.mount.now(), r.mount.site)
            await r.mount.goto_equatorial(ra2, dec2)
            await r.mount.wait_for_slew(timeout_s=15.0)
            assert not _running(r.mount)
            state = await r.mount.refresh()
            assert state.ra_j2000_hours is not None
            assert state.dec_j2000_deg is not None
            landed = angular_separation_deg(
                state.ra_j2000_hours * 15, state.dec_j2000_deg, ra2 * 15, dec2
            )
            assert landed < 0.05, f"the goto landed {landed:.3f}° away"
            assert _hand_control_tracking(r.sim) is TrackingMode.ALT_AZ
            assert not r.mount.guard.rate_motions
            # An abort ends it too: both axes stopped, tracking given back ('T 1').
            await r.mount.set_tracking_rates(*MOON_LIKE)
            assert _running(r.mount)
            del commands[:]
            await r.mount.abort()
            await r.mount.wait_for(lambda s: not r.mount.custom_rates_running, 5.0)
        stops = {c.axis for c in commands if isinstance(c, FixedRateSlew) and c.rate == 0}
        hand_backs = [c.mode for c in commands if isinstance(c, SetTrackingMode)]
        assert len(stops) == 2, commands
        assert hand_backs, commands
        assert hand_backs[-1] == Tracking.ALT_AZ, commands
        assert _hand_control_tracking(r.sim) is TrackingMode.ALT_AZ
        assert not r.mount.guard.rate_motions
