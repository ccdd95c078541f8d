"""Issue #11 part 6: the SynScan driver reopens a lost link by itself.

The real SynScan emulator on TCP closes its port while an axis turns at a rate (the stop the
driver then owes cannot be sent) and comes back on the same port. While it is gone the driver
reads as disconnected and claims no motion; once it is back the poller reopens the link,
identifies the hand control again, sends the owed stop first and polls again within 5 s.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from datetime import UTC, datetime

import pytest

from scopelink.astro import Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import MountAxis, MountState, NotConnectedError
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(latitude_deg=48.0, longitude_deg=11.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
RECONNECT_WITHIN_S = 5.0


async def wait_for(
    driver: SynScanMount, predicate: Callable[[MountState], bool], seconds: float
) -> float:
    loop = asyncio.get_running_loop()
    start = loop.time()
    try:
        await driver.wait_for(predicate, timeout_s=seconds)
    except TimeoutError:
        raise AssertionError(f"not within {seconds} s; last state {driver.state}") from None
    return loop.time() - start


async def test_the_driver_reconnects_on_the_same_port_and_sends_the_owed_stop_first() -> None:
    sim = SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=1.0))
    await sim.connect()
    async with SynScanEmulator(sim, wire=None) as emulator:
        _, port = await emulator.on_tcp("127.0.0.1", 0)
        driver = SynScanMount(f"tcp://127.0.0.1:{port}", site=SITE, timeout_s=1.0)
        await driver.connect()
        async with driver.watching():
            await driver.move_axis(MountAxis.PRIMARY, 0.5)
            assert driver.state.slewing
            before = sim.counters_at(sim.elapsed())
            links_before = driver.wire.statistics.reconnects

            await emulator.close()  # the port goes away while the axis turns
            await wait_for(driver, lambda s: not s.connected, 3.0)
            lost = driver.state
            assert not lost.slewing, "no motion is claimed while disconnected"
            assert lost.problems, "the state says why"
            assert "not confirmed" in " ".join(lost.problems), "the owed stop is named"
            with pytest.raises(NotConnectedError, match=r"\d s old"):
                await driver.goto_horizontal(40.0, 200.0)
            await asyncio.sleep(0.3)
            moved = sim.counters_at(sim.elapsed())
            assert moved[0] - before[0] > 0.1, "the axis kept turning: nothing could stop it"

            await emulator.on_tcp("127.0.0.1", port)  # back on the same port
            took = await wait_for(
                driver, lambda s: s.connected and s.age_s() < 0.5, RECONNECT_WITHIN_S
            )
            assert took < RECONNECT_WITHIN_S
            assert driver.wire.statistics.reconnects > links_before
            await wait_for(driver, lambda s: not s.problems and not s.slewing, 2.0)
            await asyncio.sleep(0.5)  # the axis brakes (3.3°/s² on an EQ6)
            still = sim.counters_at(sim.elapsed())[0]
            await asyncio.sleep(0.3)
            # At most tracking's 0.004°/s: the owed stop went out.
            assert abs(sim.counters_at(sim.elapsed())[0] - still) < 0.01
        await driver.disconnect()
