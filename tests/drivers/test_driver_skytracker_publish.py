"""The Sky Tracker driver's published state on the real emulator: its capabilities follow the Sky
Commander's presence from one connection to the next (they are not rebuilt per reading, and must
never be stale), and each reading's alt/az and RA/Dec of date are the array path's conversion of
its J2000 position at its instant (one float position takes ``astro.one_position``)."""

from __future__ import annotations

import time
from datetime import timedelta
from pathlib import Path

import numpy as np

from scopelink.astro import Site, j2000_to_apparent, j2000_to_observed
from scopelink.mount import MountState, NotSupportedError, PierSide, TrackingMode
from scopelink.servers.faults import Fault, FaultKind
from tests.support.skytracker_driver import SITE, Rig, rig, separation_deg, sky_at

MILLIARCSEC_DEG = 1e-3 / 3600.0


def commander_present(r: Rig) -> bool | None:
    """A function, so type checkers do not narrow the property between connections."""
    return r.driver.commander_present


async def test_capabilities_follow_the_commander_and_readings_are_converted_exactly(
    tmp_path: Path,
) -> None:
    # A stepped clock: a reading's status and position share one instant (read_at).
    async with rig(tmp_path, "tcp", connect=False, pace=False, clock_rate=0.0) as r:
        silent = r.emulator.commander_faults.add(Fault(FaultKind.DROP, times=None))
        await r.driver.connect()  # no Sky Commander answers on the bus
        assert commander_present(r) is False
        caps = r.driver.capabilities
        assert not caps.can_goto
        assert not caps.can_sync
        assert TrackingMode.LUNAR not in caps.tracking_modes
        assert caps.max_tracking_offset_arcsec_s == 0.0
        try:
            await r.driver.goto_equatorial(*sky_at(r.sim, 40.0, 90.0))
        except NotSupportedError:
            pass
        else:
            raise AssertionError("a GOTO without a Sky Commander was accepted")
        await r.driver.disconnect()

        r.emulator.commander_faults.remove(silent)
        await r.driver.connect()
        assert commander_present(r) is True
        caps = r.driver.capabilities
        assert caps.can_goto
        assert caps.can_sync
        assert TrackingMode.LUNAR in caps.tracking_modes
        assert caps.max_tracking_offset_arcsec_s > 0.0

        for alt_deg, az_deg in [(35.0, 120.0), (62.0, 300.0), (15.0, 45.0), (80.0, 181.0)]:
            r.point(alt_deg, az_deg)
            r.sim.step(0.7)  # each reading at its own instant
            before_s = time.monotonic()
            state = await r.driver.refresh()
            # Each reading's age counts from its own reply: the status's, then the position's
            # (the last reply of the refresh; its 'q' has none).
            assert state.position_received_s == r.driver.line.last_answer_s
            assert before_s <= state.received_s <= state.position_received_s <= time.monotonic()
            assert state.ra_j2000_hours is not None
            assert state.dec_j2000_deg is not None
            ra, dec = np.array([state.ra_j2000_hours]), np.array([state.dec_j2000_deg])
            alt, az = j2000_to_observed(ra, dec, state.read_at, SITE)
            ra_date, dec_date = j2000_to_apparent(ra, dec, state.read_at)
            assert state.alt_deg is not None
            assert state.az_deg is not None
            assert state.ra_of_date_hours is not None
            assert state.dec_of_date_deg is not None
            assert abs(state.alt_deg - alt_deg) < 0.05
            assert abs(state.alt_deg - float(np.asarray(alt)[0])) < MILLIARCSEC_DEG
            assert abs(state.az_deg - float(np.asarray(az)[0])) < 2 * MILLIARCSEC_DEG
            ra_apart_deg = 15.0 * abs(state.ra_of_date_hours - float(np.asarray(ra_date)[0]))
            assert ra_apart_deg < 2 * MILLIARCSEC_DEG
            assert abs(state.dec_of_date_deg - float(np.asarray(dec_date)[0])) < MILLIARCSEC_DEG
            assert r.driver.state.alt_deg == state.alt_deg  # published as returned


def _assert_converted(state: MountState, site: Site) -> None:
    """The state's alt/az and RA/Dec of date are its J2000 reading's at its instant and site."""
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    assert state.alt_deg is not None
    assert state.az_deg is not None
    assert state.ra_of_date_hours is not None
    assert state.dec_of_date_deg is not None
    ra, dec = np.array([state.ra_j2000_hours]), np.array([state.dec_j2000_deg])
    alt, az = j2000_to_observed(ra, dec, state.read_at, site)
    ra_date, dec_date = j2000_to_apparent(ra, dec, state.read_at)
    assert abs(state.alt_deg - float(np.asarray(alt)[0])) < MILLIARCSEC_DEG
    assert abs(state.az_deg - float(np.asarray(az)[0])) < 2 * MILLIARCSEC_DEG
    assert 15.0 * abs(state.ra_of_date_hours - float(np.asarray(ra_date)[0])) < 2 * MILLIARCSEC_DEG
    assert abs(state.dec_of_date_deg - float(np.asarray(dec_date)[0])) < MILLIARCSEC_DEG


async def test_a_reading_is_converted_once_and_every_change_reaches_the_next_state(
    tmp_path: Path,
) -> None:
    """A reading's alt/az and RA/Dec of date are computed once (every state published until the
    next reading keeps them), and anything they depend on reaches the very next state: a site
    elsewhere (published at once), a jump of the clock, a sync on the device (a new reading),
    a sync kept on the PC and its removal."""
    async with rig(tmp_path, "tcp", pace=False, clock_rate=0.0) as r:
        r.point(35.0, 120.0)
        first = await r.driver.refresh()
        _assert_converted(first, SITE)
        # Every field where it belongs (_publish_now passes them positionally).
        assert first.connected is True
        assert first.pier_side is PierSide.UNKNOWN
        assert first.slewing is False
        assert first.tracking is TrackingMode.OFF
        assert (first.parked, first.aligned, first.pulse_guiding) == (False, True, False)
        assert first.problems == ()
        assert first.position_received_s == r.driver.line.last_answer_s
        assert first.received_s < first.position_received_s
        await r.driver.set_tracking(TrackingMode.ALT_AZ)  # a command publishes again: kept
        assert r.driver.state.alt_deg == first.alt_deg

        sydney = Site(-33.86, 151.21, pressure_hpa=0.0)
        await r.driver.set_site(sydney)
        assert r.driver.state.read_at == first.read_at  # the same reading, at the new site
        assert r.driver.state.ra_j2000_hours == first.ra_j2000_hours
        _assert_converted(r.driver.state, sydney)
        assert r.driver.state.alt_deg != first.alt_deg
        await r.driver.set_site(SITE)

        r.sim.step(3 * 3600.0)  # a jump of the clock: 3 h on (new contexts, a new instant)
        jumped = await r.driver.refresh()
        assert jumped.read_at == first.read_at + timedelta(hours=3)
        _assert_converted(jumped, SITE)

        target = sky_at(r.sim, 36.0, 121.0)
        await r.driver.sync_equatorial(*target)  # on the device: the Sky Commander realigns
        synced = await r.driver.refresh()
        _assert_converted(synced, SITE)
        assert synced.ra_j2000_hours is not None
        assert synced.dec_j2000_deg is not None
        assert separation_deg((synced.ra_j2000_hours, synced.dec_j2000_deg), target) < 0.02

        r.driver.syncs_on_device = False  # kept on the PC: the next state is corrected
        r.sim.step(1.0)
        await r.driver.refresh()
        offset = sky_at(r.sim, 36.5, 121.0)
        await r.driver.sync_equatorial(*offset)
        kept = await r.driver.refresh()
        assert r.driver.pointing.active
        assert kept.ra_j2000_hours is not None
        assert kept.dec_j2000_deg is not None
        assert separation_deg((kept.ra_j2000_hours, kept.dec_j2000_deg), offset) < 0.02
        assert kept.alt_deg is not None
        assert abs(kept.alt_deg - 36.5) < 0.05
        r.driver.pointing.clear()
        r.driver.pointing_changed()
        raw = await r.driver.refresh()
        assert raw.alt_deg is not None
        assert abs(raw.alt_deg - 36.0) < 0.05
        _assert_converted(raw, SITE)
