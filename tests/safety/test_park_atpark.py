"""Issue #11 part 4: AtPark only once the mount has arrived at the park position and stopped
(docs/reliability-safety.md, "Parking"). During the park slew Slewing is true, AtPark false,
motion other than a stop is refused, and an abort leaves the mount unparked where it stopped."""

from __future__ import annotations

from pathlib import Path

import pytest
from alpaca.exceptions import ParkedException
from alpaca.telescope import TelescopeAxes

from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Limits, MountAxis, NotSupportedError, ParkedError, ParkPosition
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.alpaca import (
    WATCHABLE_SPEED_UP,
    blocking,
    client,
    serve,
    sim_mount,
    wait_until,
)
from tests.support.skytracker_driver import rig as skytracker_rig
from tests.support.synscan_driver import MADRID, START
from tests.support.synscan_driver import rig as synscan_rig
from tests.support.web import served

SLEW_TIMEOUT_S = 20.0


async def test_alpaca_atpark_is_false_during_the_park_slew_and_true_once_arrived(
    tmp_path: Path,
) -> None:
    mount = sim_mount(speed_up=WATCHABLE_SPEED_UP)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await blocking(lambda: setattr(telescope, "Connected", True))
        await blocking(lambda: telescope.SlewToAltAzAsync(250.0, 30.0))
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")

        await blocking(telescope.Park)
        # Read all three in one go: the slew lasts a few real seconds at x20.
        at_park, slewing, device_state = await blocking(
            lambda: (telescope.AtPark, telescope.Slewing, telescope.DeviceState)
        )
        assert (at_park, slewing) == (False, True)
        values = {item["Name"]: item["Value"] for item in device_state}
        assert values["AtPark"] is False
        with pytest.raises(ParkedException):  # 0x408: on its way to park
            await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisPrimary, 1.0))

        def parked_and_still() -> bool:
            at_park = telescope.AtPark
            if at_park:
                assert not telescope.Slewing
            return bool(at_park)

        await wait_until(parked_and_still, SLEW_TIMEOUT_S, "AtPark")
        assert mount.state.parked
        assert not mount.state.slewing


async def test_alpaca_abort_during_the_park_slew_leaves_the_mount_unparked(
    tmp_path: Path,
) -> None:
    mount = sim_mount(speed_up=WATCHABLE_SPEED_UP)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await blocking(lambda: setattr(telescope, "Connected", True))
        await blocking(lambda: telescope.SlewToAltAzAsync(250.0, 30.0))
        await wait_until(lambda: not telescope.Slewing, SLEW_TIMEOUT_S, "the slew's end")
        await blocking(telescope.Park)
        await blocking(telescope.AbortSlew)
        await wait_until(lambda: not telescope.Slewing, 5.0, "the stop")
        assert await blocking(lambda: telescope.AtPark) is False
        await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisPrimary, 0.0))  # unparked
        mount.step(120.0)  # long after the park would have landed: still not parked
        assert await blocking(lambda: telescope.AtPark) is False


async def test_dashboard_shows_parked_only_after_arrival() -> None:
    async with served() as s:
        await s.mount.goto_horizontal(30.0, 250.0)
        await s.mount.wait_for_slew(timeout_s=SLEW_TIMEOUT_S)
        status, body = await s.post("/api/park")
        assert status == 200, body
        assert body["state"]["slewing"] is True
        assert body["state"]["parked"] is False
        status, body = await s.post("/api/goto", {"alt_deg": 40.0, "az_deg": 100.0})
        assert status == 409
        assert body["kind"] == "ParkedError"
        state = await s.mount.wait_for(lambda state: state.parked, timeout_s=SLEW_TIMEOUT_S)
        assert not state.slewing
        status, body = await s.get("/api/state")
        assert body["state"]["parked"] is True


@pytest.mark.parametrize("transport", ["tcp"])
async def test_synscan_driver_parked_only_once_the_park_goto_has_landed(transport: str) -> None:
    async with synscan_rig(transport) as r:
        r.mount.park_position = ParkPosition(alt_deg=30.0, az_deg=200.0)
        await r.mount.park()
        state = await r.mount.refresh()
        assert state.slewing
        assert not state.parked
        with pytest.raises(ParkedError, match="on its way"):
            await r.mount.move_axis(MountAxis.PRIMARY, 1.0)
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert state.parked
        assert not state.slewing


@pytest.mark.parametrize("transport", ["tcp"])
async def test_synscan_driver_abort_cancels_the_park(transport: str) -> None:
    async with synscan_rig(transport) as r:
        r.mount.park_position = ParkPosition(alt_deg=30.0, az_deg=200.0)
        await r.mount.park()
        r.sim.step(1.0)
        await r.mount.abort()
        r.sim.step(120.0)
        state = await r.mount.refresh()
        assert not state.parked
        assert not state.slewing
        await r.mount.move_axis(MountAxis.PRIMARY, 0.0)  # not refused: unparked


async def test_synscan_driver_not_parked_when_the_park_goto_ends_elsewhere() -> None:
    """The hand control ignores the park goto (here: its own horizon is above the park
    position): the goto 'ends' at once, away from the park position, so the mount is not
    parked, says why, and still refuses motion until unparked or aborted."""
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock.stepped(START), limits=Limits(40.0))
    async with SynScanEmulator(sim) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(f"tcp://{host}:{port}", site=MADRID, clock=sim.now)
        await mount.connect()
        try:
            mount.park_position = ParkPosition(alt_deg=30.0, az_deg=200.0)
            await mount.park()
            sim.step(120.0)
            state = await mount.refresh()
            assert not state.slewing
            assert not state.parked
            assert any("not parked" in problem for problem in state.problems)
            with pytest.raises(ParkedError):
                await mount.move_axis(MountAxis.PRIMARY, 1.0)
            await mount.abort()
            await mount.move_axis(MountAxis.PRIMARY, 0.0)
        finally:
            await mount.disconnect()


async def test_the_sky_tracker_cannot_park_and_never_reads_parked(tmp_path: Path) -> None:
    async with skytracker_rig(tmp_path, "tcp") as r:
        assert not r.driver.capabilities.can_park
        with pytest.raises(NotSupportedError):
            await r.driver.park()
        assert not (await r.driver.refresh()).parked
