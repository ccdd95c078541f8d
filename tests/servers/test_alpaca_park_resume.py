"""Issue #15 part 2 through Alpaca (alpyca): SetPark, Park, power-cycle the emulated hand control,
Unpark, and a goto lands within 0.1° of the star without a new alignment (docs/parking.md)."""

from __future__ import annotations

from pathlib import Path

import pytest
from alpaca.telescope import Telescope

from scopelink.drivers.synscan import SynScanMount
from scopelink.servers.alpaca import AlpacaServer, EquatorialSystem, TelescopeConfig
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.alpaca import SITE, SPEED_UP, blocking, client, radec_at, wait_until
from tests.support.parking import tube_altaz, tube_off_target_deg


def _connect(telescope: Telescope) -> None:
    telescope.Connected = True


async def test_alpaca_unpark_after_a_power_cycle_and_the_goto_lands_within_a_tenth_of_a_degree(
    tmp_path: Path,
) -> None:
    sim = SimulatedMount(EQ6, site=SITE, clock=SimClock.accelerated(SPEED_UP))
    async with SynScanEmulator(sim) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(f"tcp://{host}:{port}", site=SITE, clock=sim.now)
        mount.park_keeper.enable(tmp_path / "state")
        await mount.connect()
        config = TelescopeConfig(equatorial_system=EquatorialSystem.J2000)
        server = AlpacaServer(
            mount, port=0, discovery_port=None, state_dir=tmp_path / "alpaca", config=config
        )
        try:
            async with mount.watching(), server:
                telescope = client(server)
                await blocking(lambda: _connect(telescope))
                # Park where the observer chose: slew there, SetPark, Park.
                await blocking(lambda: setattr(telescope, "Tracking", False))
                await blocking(lambda: telescope.SlewToAltAzAsync(230.0, 30.0))
                await wait_until(lambda: not telescope.Slewing, 30.0, "the slew to the park")
                await blocking(telescope.SetPark)
                await blocking(telescope.Park)
                await wait_until(lambda: telescope.AtPark, 30.0, "AtPark")
                parked_tube = tube_altaz(sim)

                await emulator.power_cycle()  # the tube stays; the counters and alignment go
                assert tube_altaz(sim) == pytest.approx(parked_tube, abs=1e-9)
                assert not emulator.hand_control.aligned

                await blocking(telescope.Unpark)
                assert "restored" in mount.park_keeper.last_resume, mount.park_keeper.last_resume
                assert not await blocking(lambda: telescope.AtPark)
                await blocking(lambda: setattr(telescope, "Tracking", True))
                ra, dec = radec_at(sim, 55.0, 120.0)  # a star far from the park position
                await blocking(lambda: telescope.SlewToCoordinatesAsync(ra, dec))
                await wait_until(lambda: not telescope.Slewing, 60.0, "the goto to land")
                assert not emulator.hand_control.aligned  # no new alignment was made
                assert tube_off_target_deg(sim, ra, dec) <= 0.1
                await blocking(lambda: setattr(telescope, "Connected", False))
        finally:
            await mount.disconnect()
