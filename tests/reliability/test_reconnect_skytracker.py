"""Issue #11 part 6: the Sky Tracker driver reopens a lost link by itself.

The real Sky Tracker emulator on TCP closes its port (a network bridge restarting, a cable pulled)
while an arrow is pressed, and comes back on the same port. While it is gone the driver reads as
disconnected and claims no motion; once it is back the poller reopens the link, identifies the box
again (releasing the arrow the broken link left pressed) and polls again within 5 s.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from pathlib import Path

from scopelink.drivers.skytracker import BusOptions, SkyTrackerMount
from scopelink.mount import MountAxis, MountState, TrackingMode
from scopelink.servers.faults import ANY, Fault, FaultKind
from scopelink.servers.skytracker import SkyTrackerEmulator
from tests.support.skytracker_driver import SITE, sky_tracker_mount

BUS = BusOptions(retry_delays_s=(0.05, 0.1, 0.2))
TIMEOUT_S = 0.5
RECONNECT_WITHIN_S = 5.0


async def wait_for(
    driver: SkyTrackerMount, predicate: Callable[[MountState], bool], seconds: float
) -> float:
    """Seconds until a published state satisfies ``predicate`` (AssertionError after
    ``seconds``)."""
    loop = asyncio.get_running_loop()
    start = loop.time()
    try:
        await driver.wait_for(predicate, timeout_s=seconds)
    except TimeoutError:
        raise AssertionError(f"not within {seconds} s; last state {driver.state}") from None
    return loop.time() - start


async def test_the_driver_reconnects_by_itself_and_claims_no_motion_meanwhile(
    tmp_path: Path,
) -> None:
    sim = sky_tracker_mount(rate=1.0)
    # Well above the horizon: level at the north, tracking plus the arrow could sink below 0°
    # within the test on a slow machine, and the guard would rightly stop it (a problem).
    sim.set_axis_position(MountAxis.SECONDARY, 45.0)
    async with SkyTrackerEmulator(sim, tmp_path) as emulator:
        _, port = await emulator.on_tcp()
        driver = SkyTrackerMount(f"tcp://127.0.0.1:{port}", site=SITE, timeout_s=TIMEOUT_S, bus=BUS)
        driver.stale_after_s = 1.0
        await driver.connect()
        async with driver.watching():
            await driver.set_tracking(TrackingMode.ALT_AZ)
            await driver.move_axis(MountAxis.PRIMARY, 1.0)
            assert driver.state.slewing
            polls_before = driver.poller.polls

            await emulator.close()  # the box's port goes away, its arrow still pressed
            await wait_for(driver, lambda s: not s.connected, 3.0)
            lost = driver.state
            assert not lost.slewing, "no motion is claimed while disconnected"
            assert lost.tracking is TrackingMode.OFF
            assert lost.problems, "the state says why"
            await asyncio.sleep(0.5)
            assert not driver.state.connected

            await emulator.on_tcp("127.0.0.1", port)  # back on the same port
            took = await wait_for(
                driver, lambda s: s.connected and s.age_s() < 0.5, RECONNECT_WITHIN_S
            )
            assert took < RECONNECT_WITHIN_S
            await wait_for(driver, lambda s: driver.poller.polls > polls_before + 2, 2.0)
            state = driver.state
            assert state.connected
            assert not state.problems
            assert not state.slewing, "the arrow the lost link left pressed was released"
            assert state.tracking is TrackingMode.ALT_AZ, "tracking carried on"
            assert state.alt_deg is not None
        await driver.disconnect()


async def test_a_silent_box_is_lost_then_found_again(tmp_path: Path) -> None:
    sim = sky_tracker_mount(rate=1.0)
    # Well above the horizon: level at the north, tracking plus the arrow could sink below 0°
    # within the test on a slow machine, and the guard would rightly stop it (a problem).
    sim.set_axis_position(MountAxis.SECONDARY, 45.0)
    async with SkyTrackerEmulator(sim, tmp_path) as emulator:
        _, port = await emulator.on_tcp()
        driver = SkyTrackerMount(f"tcp://127.0.0.1:{port}", site=SITE, timeout_s=TIMEOUT_S, bus=BUS)
        driver.stale_after_s = 1.0
        await driver.connect()
        async with driver.watching():
            emulator.faults.add(Fault(FaultKind.STALL, ANY))
            await wait_for(driver, lambda s: not s.connected, 5.0)
            engaged = driver.engaged
            assert engaged, "still to be connected: the poller keeps trying"
            emulator.faults.clear()
            await wait_for(
                driver, lambda s: s.connected and s.age_s() < 0.5, RECONNECT_WITHIN_S + 1.0
            )
        await driver.disconnect()
        assert not driver.engaged
        assert not driver.state.connected
