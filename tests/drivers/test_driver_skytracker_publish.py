"""The Sky Tracker driver's published state on the real emulator: its capabilities follow the Sky
Commander's presence from one connection to the next (they are not rebuilt per reading, and must
never be stale), and each reading's alt/az and RA/Dec of date are the array path's conversion of
its J2000 position at its instant (one float position takes ``astro.one_position``)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from scopelink.astro import j2000_to_apparent, j2000_to_observed
from scopelink.mount import NotSupportedError, TrackingMode
from scopelink.servers.faults import Fault, FaultKind
from tests.support.skytracker_driver import SITE, Rig, rig, sky_at

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
