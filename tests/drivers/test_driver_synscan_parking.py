"""Issue #15 part 2 on the SynScan driver against the real emulator: park, power cycle, unpark
restores the axis positions with "set axis position", gotos land without a new alignment
(docs/parking.md)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from scopelink.astro import angular_separation_deg
from scopelink.drivers.synscan import NotAlignedError, SynScanMount
from scopelink.drivers.synscan.parking import (
    POLE_AMBIGUITY_DEG,
    POWER_ON_TOLERANCE_DEG,
    REFINE_PASSES,
    RESTORE_TOLERANCE_DEG,
    STILL_DEG,
    SlowGotoRefusedError,
)
from scopelink.mount import Limits, MountState, ParkPosition
from scopelink.mount.parking import ParkRecordError
from scopelink.protocol.synscan import Axis, FixedRateSlew, SlowGoto
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.parking import settle, tube_off_target_deg
from tests.support.synscan_driver import MADRID, START, Rig, rig


def _records(directory: Path) -> list[Path]:
    return list(directory.rglob("park.json"))


def _record(directory: Path) -> dict[str, object]:
    [path] = _records(directory)
    data: dict[str, object] = json.loads(path.read_text())
    return data


def _edit(path: Path, **values: float) -> None:
    data = json.loads(path.read_text())
    data.update(values)
    path.write_text(json.dumps(data))


def _off_deg(state: MountState, other: MountState) -> float:
    assert state.alt_deg is not None
    assert state.az_deg is not None
    assert other.alt_deg is not None
    assert other.az_deg is not None
    return float(angular_separation_deg(state.az_deg, state.alt_deg, other.az_deg, other.alt_deg))


async def _park_at(r: Rig, tmp_path: Path, park: ParkPosition) -> MountState:
    r.mount.park_keeper.enable(tmp_path)
    r.mount.park_position = park
    await r.mount.park()
    state = await settle(r)
    assert state.parked
    return state


async def test_park_power_cycle_unpark_and_a_goto_lands_without_a_new_alignment(
    tmp_path: Path,
) -> None:
    async with rig() as r:
        parked = await _park_at(r, tmp_path, ParkPosition(alt_deg=35.0, az_deg=220.0))
        record = _record(tmp_path)
        assert record["aligned"] is True
        assert record["axes_deg"] is not None

        await r.emulator.power_cycle()
        assert not r.emulator.hand_control.aligned
        assert _off_deg(await r.mount.refresh(), parked) > 10  # the counters restarted

        resume = await r.mount.unpark()
        assert resume.restored, resume.message
        assert "restored" in resume.message
        state = await r.mount.refresh()
        assert _off_deg(state, parked) < 0.01
        assert not _records(tmp_path)  # consumed

        ra, dec = r.sim.j2000_at(r.sim.elapsed())  # a star well away from the park position
        ra, dec = (ra + 3.0) % 24.0, 50.0
        await r.mount.goto_equatorial(ra, dec)
        await settle(r)
        # the issue's bound is 0.1°; measured 0.5" with the refining passes (docs/parking.md)
        assert tube_off_target_deg(r.sim, ra, dec) <= 0.01
        r.sim.step(600.0)  # and it tracks
        assert tube_off_target_deg(r.sim, ra, dec) <= 0.01


async def test_the_default_park_goes_home_by_slow_goto_and_records_it(tmp_path: Path) -> None:
    async with rig() as r:
        r.mount.park_keeper.enable(tmp_path / "home")
        await r.mount.park()
        assert (await settle(r)).parked
        assert _record(tmp_path / "home")["axes_deg"] == [0.0, 90.0]
        assert [axis.position for axis in r.sim.axes] == pytest.approx([0.0, 90.0], abs=1e-4)


async def test_park_at_axis_positions_lands_on_the_counters(tmp_path: Path) -> None:
    async with rig() as r:
        r.mount.park_keeper.enable(tmp_path)
        r.mount.park_position = r.mount.park_position_at_axes(-30.0, 60.0)
        await r.mount.park()
        assert (await settle(r)).parked
        assert [a.position for a in r.sim.axes] == pytest.approx([-30.0, 60.0], abs=1e-4)
        assert _record(tmp_path)["axes_deg"] == [-30.0, 60.0]


async def test_a_stale_record_is_not_restored_into_an_aligned_hand_control(tmp_path: Path) -> None:
    async with rig() as r:
        await _park_at(r, tmp_path, ParkPosition(alt_deg=35.0, az_deg=220.0))
        [path] = _records(tmp_path)  # the record disagrees: the tube was moved since
        _edit(path, alt_deg=60.0, az_deg=100.0)
        counters = [axis.position for axis in r.sim.axes]
        resume = await r.mount.unpark()  # the hand control is still aligned
        assert not resume.restored
        assert "stale" in resume.message
        assert "max_sync_deg" in resume.message
        assert [axis.position for axis in r.sim.axes] == counters  # nothing was set
        assert not (await r.mount.refresh()).parked
        assert not path.exists()


async def test_no_restore_when_the_axes_moved_after_power_on(tmp_path: Path) -> None:
    async with rig() as r:
        await _park_at(r, tmp_path, ParkPosition(alt_deg=35.0, az_deg=220.0))
        await r.emulator.power_cycle()
        # the keypad's slow goto, through the hand control
        await r.emulator.hand_control.answer(SlowGoto.from_degrees(Axis.ALT_DEC, 60.0))
        await settle(r)
        resume = await r.mount.unpark()
        assert not resume.restored
        assert "power-on" in resume.message
        with pytest.raises(NotAlignedError):
            await r.mount.goto_equatorial(5.0, 50.0)


async def test_nothing_is_restored_while_the_mount_moves(tmp_path: Path) -> None:
    async with rig() as r:
        await _park_at(r, tmp_path, ParkPosition(alt_deg=35.0, az_deg=220.0))
        await r.emulator.power_cycle()
        # a slow goto that ends where the counters started: still "at power-on" when it lands
        await r.emulator.hand_control.answer(SlowGoto.from_degrees(Axis.AZM_RA, 0.5))
        with pytest.raises(ParkRecordError, match="moving"):
            await r.mount.unpark()
        assert _records(tmp_path)  # kept for the next try
        await settle(r)
        assert (await r.mount.unpark()).restored


def _resumed(r: Rig) -> bool:
    return r.mount.resumed


async def test_a_reconnect_ends_the_resumed_gotos(tmp_path: Path) -> None:
    """A lost link may have been a power cycle: the restored counters cannot be trusted."""
    async with rig() as r:
        await _park_at(r, tmp_path, ParkPosition(alt_deg=35.0, az_deg=220.0))
        await r.emulator.power_cycle()
        assert (await r.mount.unpark()).restored
        assert _resumed(r)
        await r.mount.disconnect()
        await r.mount.connect()
        assert not _resumed(r)
        with pytest.raises(NotAlignedError):
            await r.mount.goto_equatorial(5.0, 50.0)


def test_the_documented_limits_are_the_code_s() -> None:
    text = " ".join((Path(__file__).parents[2] / "docs" / "parking.md").read_text().split())
    assert f"within {POWER_ON_TOLERANCE_DEG:g}° (`POWER_ON_TOLERANCE_DEG`)" in text
    assert f"within {RESTORE_TOLERANCE_DEG:g}° (`RESTORE_TOLERANCE_DEG`)" in text
    assert f"within {POLE_AMBIGUITY_DEG:g}° (`POLE_AMBIGUITY_DEG`)" in text
    assert f"`REFINE_PASSES` = {REFINE_PASSES}" in text
    assert f"more than {STILL_DEG:g}° (`STILL_DEG`)" in text
    assert f"limits.max_sync_deg {Limits().max_sync_deg:g}°" in text


async def test_the_default_park_falls_back_to_b_where_slow_gotos_are_refused(
    tmp_path: Path,
) -> None:
    """A bridge (``scopelink serve``) answers slow gotos as failed passthroughs."""
    sim = SimulatedMount(EQ6, site=MADRID, clock=SimClock.stepped(START))
    async with SynScanEmulator(sim, axis_passthrough=False) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(f"tcp://{host}:{port}", site=MADRID, clock=sim.now)
        await mount.connect()
        try:
            await mount.park()
            for _ in range(100):
                sim.step(5.0)
                state = await mount.refresh()
                if not state.slewing:
                    break
            assert state.parked
            assert state.alt_deg == pytest.approx(MADRID.latitude_deg, abs=0.6)  # the pole
            mount.park_position = mount.park_position_at_axes(-30.0, 60.0)
            await mount.unpark()
            with pytest.raises(SlowGotoRefusedError):  # given as axes: no other way
                await mount.park()
        finally:
            await mount.disconnect()


async def test_nothing_is_restored_during_a_keypad_slew_which_l_does_not_report(
    tmp_path: Path,
) -> None:
    async with rig(clock=SimClock.accelerated(50.0, START)) as r:
        r.mount.park_keeper.enable(tmp_path)
        r.mount.park_position = ParkPosition(alt_deg=35.0, az_deg=220.0)
        await r.mount.park()
        await r.mount.wait_for(lambda state: state.parked, timeout_s=30.0)
        await r.emulator.power_cycle()
        # the keypad's Dec arrow at speed 4 (32x sidereal): 'L' says no goto runs. (The RA
        # axis turning at the pole changes no reading: the read-back after the restore catches it)
        await r.emulator.hand_control.answer(FixedRateSlew(Axis.ALT_DEC, positive=False, rate=4))
        with pytest.raises(ParkRecordError, match="moving"):
            await r.mount.unpark()
        assert _records(tmp_path)  # kept for the next try


async def test_an_unaligned_hand_control_is_not_parked_by_axis_positions() -> None:
    """Unaligned (and not resumed) the counters say nothing of where the tube points."""
    async with rig() as r:
        await r.emulator.power_cycle()
        r.mount.park_position = r.mount.park_position_at_axes(-30.0, 60.0)
        counters = [axis.position for axis in r.sim.axes]
        with pytest.raises(NotAlignedError):
            await r.mount.park()
        r.sim.step(60.0)
        assert [axis.position for axis in r.sim.axes] == counters
