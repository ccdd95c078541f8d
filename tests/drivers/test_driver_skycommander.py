"""The Sky Commander's memory and push-to (issue #15 part 4): ``SkyCommanderMount`` on the Sky
Commander emulator alone, ``SkyTrackerMount.store_object`` through the Sky Tracker's bus, the
slot mirror and the push-to figures, all against the real emulators over TCP."""

from __future__ import annotations

import inspect
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest

from scopelink.cli.skycommander_command import DEFAULT_PUSHTO_INTERVAL_S, MAX_PLAN_BYTES
from scopelink.drivers.skytracker import DEFAULT_TIMEOUT_S, SkyCommanderMount
from scopelink.drivers.skytracker.base import BAUDRATE
from scopelink.drivers.skytracker.exchange import RESYNC_QUIET_S
from scopelink.drivers.skytracker.memory import (
    SLOT_COUNT,
    SUN_DRIFT_MARGIN_DEG,
    SlotEntry,
    SlotMirror,
    UploadInterruptedError,
    placeholder,
    upload,
)
from scopelink.drivers.skytracker.pushto import ON_TARGET_DEG, push_to
from scopelink.drivers.skytracker.realign import SYNC_TOLERANCE_DEG
from scopelink.mount import InvalidValueError, MountAxis, NotConnectedError, NotSupportedError
from scopelink.protocol.skytracker import LoadObject
from scopelink.servers.faults import Fault, FaultKind
from scopelink.servers.skytracker import SkyCommanderEmulator
from scopelink.servers.skytracker.objects import StoredObject
from scopelink.sim import SimulatedMount
from tests.support.skytracker_driver import SITE, rig, sky_at, sky_tracker_mount


@asynccontextmanager
async def commander_rig(
    data_dir: Path,
) -> AsyncIterator[tuple[SkyCommanderEmulator, SimulatedMount, SkyCommanderMount]]:
    sim = sky_tracker_mount(rate=1.0)
    sim.set_axis_position(MountAxis.PRIMARY, 120.0)
    sim.set_axis_position(MountAxis.SECONDARY, 35.0)
    async with SkyCommanderEmulator(sim, data_dir) as emulator:
        host, port = await emulator.on_tcp()
        driver = SkyCommanderMount(f"tcp://{host}:{port}", site=SITE, clock=sim.clock.now)
        await driver.connect()
        try:
            yield emulator, sim, driver
        finally:
            await driver.disconnect()


async def test_a_sky_commander_alone_reads_where_the_scope_points(tmp_path: Path) -> None:
    async with commander_rig(tmp_path) as (emulator, _, driver):
        state = await driver.refresh()
        ra, dec = emulator.commander.position_j2000()
        assert state.connected
        assert state.ra_j2000_hours == pytest.approx(ra, abs=0.002)
        assert state.dec_j2000_deg == pytest.approx(dec, abs=0.002)
        assert state.alt_deg == pytest.approx(35.0, abs=0.05)
        assert driver.identity.protocol == "skycommander"
        assert not driver.capabilities.can_goto
        with pytest.raises(NotSupportedError):
            await driver.goto_equatorial(ra, dec)


async def test_store_object_lands_in_the_sky_commanders_memory(tmp_path: Path) -> None:
    async with commander_rig(tmp_path) as (emulator, _, driver):
        await driver.store_object(0, 0.712, 41.269)
        await driver.store_object(58, 20.988, 44.529)
        store = emulator.commander.store
        assert store.get(0) == StoredObject(0.712, 41.269)
        assert store.get(58) == StoredObject(20.988, 44.529)
        assert emulator.commander.current_object is None  # storing does not make it current
        for slot in (59, 99, -1):
            with pytest.raises(InvalidValueError, match="00-58"):
                await driver.store_object(slot, 1.0, 2.0)
        assert set(store.items()) == {0, 58}


async def test_a_sky_commander_alone_syncs_by_realigning(tmp_path: Path) -> None:
    async with commander_rig(tmp_path) as (emulator, sim, driver):
        ra, dec = sky_at(sim, 40.0, 125.0)  # 5° off where the scope points
        await driver.sync_equatorial(ra, dec)
        assert emulator.commander.aligned
        state = await driver.refresh()
        assert state.alt_deg == pytest.approx(40.0, abs=0.05)


async def test_the_sky_tracker_stores_objects_through_its_bus(tmp_path: Path) -> None:
    async with rig(tmp_path, "tcp") as sky:
        await sky.driver.store_object(10, 5.588, -5.391)
        assert sky.emulator.commander.store.get(10) == StoredObject(5.588, -5.391)
        with pytest.raises(InvalidValueError):
            await sky.driver.store_object(99, 5.588, -5.391)
        assert sky.emulator.commander.current_object is None


async def test_upload_records_each_slot_once_acknowledged(tmp_path: Path) -> None:
    mirror = SlotMirror("skycommander-test", tmp_path / "state")
    entries = [
        SlotEntry(3, "M 31", 0.712, 41.269),
        SlotEntry(4, "M 42", 5.588, -5.391),
        SlotEntry(5, "Vega", 18.616, 38.786),
    ]
    async with commander_rig(tmp_path / "box") as (emulator, sim, driver):
        written = await upload(driver, mirror, entries, sim.clock.now())
        assert [e.slot for e in written] == [3, 4, 5]
        assert sorted(mirror.entries()) == [3, 4, 5]
        assert sorted(emulator.commander.store.items()) == [3, 4, 5]
        # A slot given twice sends nothing at all.
        with pytest.raises(InvalidValueError, match="twice"):
            await upload(
                driver, mirror, [SlotEntry(7, "a", 1, 1), SlotEntry(7, "b", 2, 2)], sim.clock.now()
            )
        assert 7 not in emulator.commander.store.items()
        # The link dies after the first slot: the mirror holds exactly what landed.
        await driver.store_object(6, 1.0, 1.0)

        class Failing:
            def __init__(self) -> None:
                self.calls = 0

            async def store_object(self, slot: int, ra: float, dec: float) -> None:
                self.calls += 1
                if self.calls == 2:
                    await driver.disconnect()
                await driver.store_object(slot, ra, dec)

        with pytest.raises(UploadInterruptedError, match="1 of 2 slots") as failure:
            await upload(
                Failing(),
                mirror,
                [SlotEntry(20, "x", 1, 1), SlotEntry(21, "y", 2, 2)],
                sim.clock.now(),
            )
        assert [e.slot for e in failure.value.written] == [20]
        assert sorted(mirror.entries()) == [3, 4, 5, 20]
        assert 21 not in emulator.commander.store.items()


async def test_push_to_figures_agree_with_the_sky_commanders_own_offsets(tmp_path: Path) -> None:
    async with commander_rig(tmp_path) as (emulator, sim, driver):
        for alt, az in ((50.0, 100.0), (20.0, 150.0), (35.5, 119.0), (60.0, 300.0)):
            ra, dec = sky_at(sim, alt, az)
            state = await driver.refresh()
            figures = push_to("target", ra, dec, state=state, when=state.read_at, site=SITE)
            emulator.commander.load(LoadObject.current(ra, dec))
            box_up, box_ccw = emulator.commander.offsets_deg()
            assert figures.up_deg == pytest.approx(box_up, abs=0.02)
            assert figures.right_deg == pytest.approx(-box_ccw, abs=0.03)
            assert figures.up_deg == pytest.approx(alt - 35.0, abs=0.05)
        on = sky_at(sim, 35.0, 120.0)
        state = await driver.refresh()
        figures = push_to("here", *on, state=state, when=state.read_at, site=SITE)
        assert figures.on_target
        assert "on target" in figures.describe()


def test_the_documented_limits_and_defaults_are_the_code_s() -> None:
    docs = Path(__file__).resolve().parents[2] / "docs"
    text = (docs / "drivers-skytracker.md").read_text(encoding="utf-8")
    section = " ".join(text[text.index("## Sky Commander memory and push-to") :].split())
    assert f"{SLOT_COUNT} objects" in section
    assert f"plus {SUN_DRIFT_MARGIN_DEG:g}° (`SUN_DRIFT_MARGIN_DEG`" in section
    assert f"within {ON_TARGET_DEG:g}° on both axes (`ON_TARGET_DEG`)" in section
    assert f"{RESYNC_QUIET_S:g} s of quiet (`RESYNC_QUIET_S`" in section
    assert f"reply timeout {DEFAULT_TIMEOUT_S:g} s (`timeout_s`" in section
    assert f"`SYNC_TOLERANCE_DEG` = {SYNC_TOLERANCE_DEG:g}°" in section
    assert f"{BAUDRATE} baud 8N1" in section
    assert inspect.signature(SkyCommanderMount).parameters["timeout_s"].default == DEFAULT_TIMEOUT_S
    assert placeholder(SITE) == (0.0, 90.0)
    assert "RA 0 h Dec +90°" in section
    cli = " ".join((docs / "cli.md").read_text(encoding="utf-8").split())
    assert f"`--interval` seconds (default {DEFAULT_PUSHTO_INTERVAL_S:g}" in cli
    assert "`--from N` (default 0)" in cli
    assert MAX_PLAN_BYTES == 1 << 20
    assert "at most 1 MiB, `MAX_PLAN_BYTES`" in cli


async def test_an_upload_during_a_goto_fails_clearly_and_records_only_what_landed(
    tmp_path: Path,
) -> None:
    mirror = SlotMirror("skycommander-goto", tmp_path / "state")
    async with rig(tmp_path / "box", "tcp") as sky:
        await sky.driver.store_object(1, 1.0, 1.0)
        await sky.driver.goto_equatorial(*sky_at(sky.sim, 60.0, 200.0))
        entries = [SlotEntry(2, "M 31", 0.712, 41.269)]
        with pytest.raises(UploadInterruptedError, match=r"GOTO is running.*0 of 1 slots"):
            await upload(sky.driver, mirror, entries, sky.sim.clock.now())
        assert mirror.entries() == {}
        assert sky.emulator.commander.store.get(2) is None
        await sky.driver.wait_for_goto(timeout_s=15.0)
        written = await upload(sky.driver, mirror, entries, sky.sim.clock.now())
        assert [e.slot for e in written] == [2]
        assert sky.emulator.commander.store.get(2) == StoredObject(0.712, 41.269)


async def test_a_link_that_closed_under_the_driver_is_opened_again(tmp_path: Path) -> None:
    async with commander_rig(tmp_path) as (emulator, _, driver):
        emulator.faults.add(Fault(FaultKind.CLOSE, "CR"))  # the next position read: link gone
        with pytest.raises(NotConnectedError):
            await driver.refresh()
        assert not driver.state.connected
        assert driver.engaged
        state = await driver.refresh()  # opened again, and read
        assert state.connected
        await driver.store_object(9, 3.0, 4.0)
        assert emulator.commander.store.get(9) == StoredObject(3.0, 4.0)
