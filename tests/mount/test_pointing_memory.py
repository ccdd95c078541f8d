"""The PC-side syncs on a Mount: corrected readings, gotos checked where the tube will point,
kept per device between runs, forgotten at a new alignment (docs/pointing.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.astro import Site, observed_to_j2000
from scopelink.mount import LimitError, Limits
from scopelink.mount.memory import DeviceMemory
from scopelink.mount.pointing import POINTING_RECORD
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(48.0, 11.0)


async def pc_synced_mount(
    tmp_path: Path, *, sync: bool = True, site: Site = SITE, limits: Limits | None = None
) -> SimulatedMount:
    """A simulated mount that keeps its syncs on the PC, at alt 40° az 200°, synced 3° higher."""
    mount = SimulatedMount(EQ6, site=site, clock=SimClock.stepped(), limits=limits)
    mount.syncs_on_device = False
    await mount.connect()
    mount.keep_pointing_in(DeviceMemory("sim-eq6", tmp_path))
    await mount.goto_horizontal(40.0, 200.0)
    mount.step(200.0)
    if sync:
        await mount.sync_equatorial(*observed_to_j2000(43.0, 200.0, mount.now(), site))
    return mount


async def test_a_sync_corrects_every_reading_and_the_device_is_not_told(tmp_path: Path) -> None:
    mount = await pc_synced_mount(tmp_path)
    assert (await mount.refresh()).alt_deg == pytest.approx(43.0, abs=1e-3)
    assert mount.state.alt_deg == pytest.approx(43.0, abs=1e-3)
    assert mount.state_at(mount.elapsed()).alt_deg == pytest.approx(40.0, abs=1e-3)
    assert mount.sync_frame.reach_deg == 0.0


async def test_a_goto_is_checked_where_the_tube_will_point(tmp_path: Path) -> None:
    """Synced 3° higher: the device goes 3° lower than the target; a target below the horizon
    is refused whatever the device's frame would say, and nothing moves."""
    mount = await pc_synced_mount(tmp_path)
    with pytest.raises(LimitError, match="horizon"):
        await mount.goto_horizontal(-1.0, 200.0)
    assert not mount.snapshot().slewing
    await mount.goto_horizontal(30.0, 200.0)
    mount.step(200.0)
    assert (await mount.refresh()).alt_deg == pytest.approx(30.0, abs=0.01)
    assert mount.state_at(mount.elapsed()).alt_deg == pytest.approx(27.0, abs=0.1)


async def test_the_syncs_are_kept_per_device_and_restored(tmp_path: Path) -> None:
    first = await pc_synced_mount(tmp_path)
    assert DeviceMemory("sim-eq6", tmp_path).load(POINTING_RECORD) is not None
    second = await pc_synced_mount(tmp_path, sync=False)
    assert len(second.pointing.syncs) == 1  # so its goto to 40° went to 37° in device terms
    assert (await second.refresh()).alt_deg == pytest.approx(40.0, abs=1e-3)
    assert second.state_at(second.elapsed()).alt_deg == pytest.approx(37.0, abs=1e-3)
    second.pointing.clear()
    assert DeviceMemory("sim-eq6", tmp_path).load(POINTING_RECORD) is None
    assert len(first.pointing.syncs) == 1


async def test_a_new_alignment_forgets_the_syncs(tmp_path: Path) -> None:
    mount = await pc_synced_mount(tmp_path)
    mount.set_aligned(False)  # switched off and on: aligned again on the keypad
    await mount.refresh()
    assert len(mount.pointing.syncs) == 1  # an unaligned mount may be resumed (#15 part 2)
    mount.set_aligned(True)
    assert (await mount.refresh()).alt_deg == pytest.approx(40.0, abs=1e-3)
    assert mount.pointing.summary()["syncs"] == []
    assert DeviceMemory("sim-eq6", tmp_path).load(POINTING_RECORD) is None


async def test_an_unreadable_record_is_reported_and_left_alone(tmp_path: Path) -> None:
    memory = DeviceMemory("sim-eq6", tmp_path)
    memory.directory.mkdir(parents=True)
    memory.path(POINTING_RECORD).write_text("{not json")
    mount = await pc_synced_mount(tmp_path)
    assert len(mount.pointing.syncs) == 1  # works this run
    assert memory.path(POINTING_RECORD).read_text() == "{not json"


async def test_a_model_that_would_move_the_sky_too_far_is_refused(tmp_path: Path) -> None:
    mount = await pc_synced_mount(tmp_path, sync=False)
    with pytest.raises(LimitError, match=r"limits\.max_sync_deg"):
        await mount.sync_equatorial(*observed_to_j2000(50.5, 200.0, mount.now(), SITE))
    assert not mount.pointing.active


async def test_syncs_of_another_site_or_beyond_lowered_limits_are_not_used(
    tmp_path: Path,
) -> None:
    await pc_synced_mount(tmp_path)
    elsewhere = await pc_synced_mount(tmp_path, sync=False, site=Site(40.0, 11.0))
    assert not elsewhere.pointing.active
    assert DeviceMemory("sim-eq6", tmp_path).load(POINTING_RECORD) is not None  # left alone
    stricter = await pc_synced_mount(tmp_path, sync=False, limits=Limits(max_sync_deg=2.0))
    assert not stricter.pointing.active
    assert DeviceMemory("sim-eq6", tmp_path).load(POINTING_RECORD) is not None
    again = await pc_synced_mount(tmp_path, sync=False)
    assert len(again.pointing.syncs) == 1


async def test_a_record_with_impossible_angles_is_not_used(tmp_path: Path) -> None:
    await pc_synced_mount(tmp_path)
    memory = DeviceMemory("sim-eq6", tmp_path)
    record = memory.load(POINTING_RECORD)
    assert record is not None
    record["syncs"][0]["reading_alt_az"] = [float("nan"), 200.0]
    memory.save(POINTING_RECORD, record)
    mount = await pc_synced_mount(tmp_path, sync=False)
    assert not mount.pointing.active
    assert (await mount.refresh()).alt_deg == pytest.approx(40.0, abs=1e-3)


async def test_a_change_while_disconnected_claims_no_connection(tmp_path: Path) -> None:
    mount = await pc_synced_mount(tmp_path)
    await mount.disconnect()
    mount.pointing.clear()
    mount.pointing_changed()  # what the dashboard's clear does
    assert not mount.state.connected
    await mount.connect()
    assert mount.state.alt_deg == pytest.approx(40.0, abs=1e-3)
