"""The synchronous facade over the SynScan driver, as a script would use it: no asyncio in sight.

The emulator runs on its own event loop in a thread (a stand-in for the hand control on the other
end of a TCP bridge); the BlockingMount runs the driver on another."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import MountAxis, TrackingMode
from scopelink.mount.blocking import BlockingMount
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.synscan_driver import MADRID, START


@contextmanager
def emulator_in_a_thread(sim: SimulatedMount) -> Iterator[str]:
    """Serve ``sim`` as a SynScan hand control on a free TCP port; yields ``tcp://host:port``."""
    loop = asyncio.new_event_loop()
    ready: list[str] = []
    started = threading.Event()
    stop = asyncio.Event()

    async def serve() -> None:
        async with SynScanEmulator(sim) as emulator:
            host, port = await emulator.on_tcp("127.0.0.1", 0)
            ready.append(f"tcp://{host}:{port}")
            started.set()
            await stop.wait()

    thread = threading.Thread(target=loop.run_until_complete, args=(serve(),), daemon=True)
    thread.start()
    try:
        assert started.wait(10.0), "the emulator did not start"
        yield ready[0]
    finally:
        loop.call_soon_threadsafe(stop.set)
        thread.join(10.0)
        loop.close()


@pytest.mark.timeout(60)
def test_blocking_facade_over_the_driver() -> None:
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock.accelerated(40.0, START))
    with (
        emulator_in_a_thread(sim) as spec,
        BlockingMount(SynScanMount(spec, site=MADRID, clock=sim.now)) as mount,
    ):
        assert mount.identity.model == "EQ6 GOTO"
        assert mount.state.connected
        mount.goto_equatorial(9.0, 10.0)
        state = mount.wait_for_slew(timeout_s=30.0)
        assert not state.slewing
        assert state.ra_j2000_hours == pytest.approx(9.0, abs=1e-4)
        assert state.dec_j2000_deg == pytest.approx(10.0, abs=1e-4)
        assert mount.refresh().tracking is TrackingMode.SIDEREAL
        mount.move_axis(MountAxis.SECONDARY, 1.0)
        assert mount.state.slewing
        mount.abort()
        assert not mount.refresh().slewing
    assert not mount.state.connected
