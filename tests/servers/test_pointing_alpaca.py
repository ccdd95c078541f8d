"""Issue #15 part 1 through ASCOM Alpaca (alpyca): a misaligned emulated hand control, the SynScan
driver, a real AlpacaServer. Syncs (SyncToCoordinates) on centred stars are kept on the PC, and
SlewToCoordinatesAsync then lands where the stars are (docs/pointing.md)."""

from __future__ import annotations

import asyncio
from pathlib import Path

from alpaca.telescope import Telescope

from scopelink.servers.alpaca import AlpacaServer, EquatorialSystem, TelescopeConfig
from tests.support.alpaca import blocking
from tests.support.pointing import FIVE_DEGREES, centre, pointing_error_arcmin, rms, settle, stars
from tests.support.synscan_driver import START, rig


async def test_alpaca_syncs_fit_the_model_and_its_gotos_land_on_the_stars(tmp_path: Path) -> None:
    config = TelescopeConfig(equatorial_system=EquatorialSystem.J2000)
    async with rig("tcp") as r:
        r.sim.misalignment = FIVE_DEGREES
        server = AlpacaServer(r.mount, host="127.0.0.1", port=0, state_dir=tmp_path, config=config)
        async with server:
            telescope = Telescope(f"127.0.0.1:{server.port}", 0)
            await blocking(lambda: setattr(telescope, "Connected", True))
            for ra, dec in stars(r.mount.site, START, 6, offset=0.0):
                await centre(r.sim, ra, dec)
                await r.mount.refresh()
                await asyncio.to_thread(telescope.SyncToCoordinates, ra, dec)
                await r.mount.refresh()  # a poll begun before the star was centred is over
                reading = await blocking(lambda: (telescope.RightAscension, telescope.Declination))
                assert abs(reading[1] - dec) < 0.02  # the reading is the synced star now
            errors = []
            for ra, dec in stars(r.mount.site, START, 8, offset=0.5):
                await asyncio.to_thread(telescope.SlewToCoordinatesAsync, ra, dec)
                settle(r.sim)
                await r.mount.refresh()
                errors.append(pointing_error_arcmin(r.sim, ra, dec))
            await blocking(lambda: setattr(telescope, "Connected", False))
    assert len(r.mount.pointing.syncs) == 6
    assert rms(errors) <= 2.0
