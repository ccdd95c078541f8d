"""Issue #11 part 2: a far sync must not move the envelope (docs/reliability-safety.md, "Syncs").

Each front end's far sync is refused with a message naming ``limits.max_sync_deg``; repeated
syncs cannot walk the frame past it; the simulator's own stops, and the refusal of a motion that
heads further out, hold in the frame the user sees after a sync.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from alpaca.exceptions import InvalidValueException
from alpaca.telescope import TelescopeAxes

from scopelink.astro import Site, observed_to_j2000
from scopelink.cli.config import ConfigError, parse_config
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import LimitError, Limits, MountAxis
from scopelink.mount.limits import DEFAULT_MAX_SYNC_DEG
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import AZ_GTI, EQ6, MountModel, SimClock, SimulatedMount
from tests.support.alpaca import blocking, client, serve, sim_mount, wait_until
from tests.support.web import served

SITE = Site(latitude_deg=50.0, longitude_deg=10.0, elevation_m=300.0)
DOCS = Path(__file__).parents[2] / "docs"


async def stepped_mount(
    model: MountModel = EQ6, *, limits: Limits | None = None, alt: float = 40.0, az: float = 200.0
) -> SimulatedMount:
    """A connected simulated mount, landed at (``alt``, ``az``) with tracking off."""
    mount = SimulatedMount(model, site=SITE, clock=SimClock.stepped(), limits=limits)
    await mount.connect()
    await mount.goto_horizontal(alt, az)
    mount.step(200.0)
    return mount


def at(mount: SimulatedMount, alt: float, az: float) -> tuple[float, float]:
    return observed_to_j2000(alt, az, mount.now(), mount.site)


async def test_alpaca_sync_to_altaz_25_degrees_off_is_refused(tmp_path: Path) -> None:
    mount = sim_mount()
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await blocking(lambda: setattr(telescope, "Connected", True))
        await blocking(lambda: telescope.SlewToAltAzAsync(200.0, 40.0))
        await wait_until(lambda: not telescope.Slewing, 20.0, "the slew's end")
        with pytest.raises(InvalidValueException, match=r"limits\.max_sync_deg"):
            await blocking(lambda: telescope.SyncToAltAz(200.0, 15.0))
        assert await blocking(lambda: telescope.Altitude) == pytest.approx(40.0, abs=0.05)
        await blocking(lambda: telescope.SyncToAltAz(200.5, 40.5))  # a plate-solve's step
        assert await blocking(lambda: telescope.Altitude) == pytest.approx(40.5, abs=0.05)


async def test_a_larger_max_sync_deg_lets_a_far_sync_through(tmp_path: Path) -> None:
    mount = sim_mount(limits=Limits(max_sync_deg=30.0))
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await blocking(lambda: setattr(telescope, "Connected", True))
        await blocking(lambda: telescope.SlewToAltAzAsync(200.0, 40.0))
        await wait_until(lambda: not telescope.Slewing, 20.0, "the slew's end")
        await blocking(lambda: telescope.SyncToAltAz(200.0, 15.0))
        assert await blocking(lambda: telescope.Altitude) == pytest.approx(15.0, abs=0.05)


async def test_dashboard_179_degree_sync_is_refused() -> None:
    async with served() as s:
        before = await s.mount.refresh()
        assert before.ra_j2000_hours is not None
        assert before.dec_j2000_deg is not None
        far = {"ra_hours": (before.ra_j2000_hours + 12.0) % 24.0, "dec_deg": -before.dec_j2000_deg}
        status, body = await s.post("/api/sync", far)
        assert status == 409, body
        assert "limits.max_sync_deg" in body["error"]
        after = await s.mount.refresh()
        assert after.dec_j2000_deg == pytest.approx(before.dec_j2000_deg, abs=0.01)


async def test_alpaca_refuses_moveaxis_further_below_the_horizon_after_a_sync(
    tmp_path: Path,
) -> None:
    """Synced 9° down, the mount reads -4°, below the 0° horizon: down is refused, up is not."""
    mount = sim_mount(AZ_GTI)
    async with serve(mount, state_dir=tmp_path) as server:
        telescope = client(server)
        await blocking(lambda: setattr(telescope, "Connected", True))
        await blocking(lambda: telescope.SlewToAltAzAsync(180.0, 5.0))
        await wait_until(lambda: not telescope.Slewing, 20.0, "the slew's end")
        await blocking(lambda: telescope.SyncToAltAz(180.0, -4.0))
        assert await blocking(lambda: telescope.Altitude) == pytest.approx(-4.0, abs=0.05)
        with pytest.raises(InvalidValueException, match="horizon"):
            await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisSecondary, -1.0))
        assert not await blocking(lambda: telescope.Slewing)
        await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisSecondary, 1.0))
        await blocking(lambda: telescope.MoveAxis(TelescopeAxes.axisSecondary, 0.0))


@pytest.mark.parametrize("synced_by", [-8.0, 8.0])
async def test_the_simulator_stops_at_the_horizon_in_the_frame_the_user_sees(
    synced_by: float,
) -> None:
    """Synced 8° lower than the truth, the simulator stops where the user's reading meets the
    horizon; synced 8° higher, where the truth does (it knows both, and honours both)."""
    mount = await stepped_mount(AZ_GTI, limits=Limits(horizon_deg=5.0), alt=20.0, az=180.0)
    await mount.sync_equatorial(*at(mount, 20.0 + synced_by, 180.0))
    await mount.move_axis(MountAxis.SECONDARY, -2.0)
    state = mount.step(60.0)
    assert not state.slewing
    assert state.alt_deg is not None
    physical_alt = state.alt_deg - synced_by
    assert min(state.alt_deg, physical_alt) == pytest.approx(5.0, abs=0.05)
    assert any("limit" in problem for problem in state.problems)


async def test_repeated_syncs_cannot_walk_the_frame_past_max_sync_deg() -> None:
    mount = await stepped_mount()
    await mount.sync_equatorial(*at(mount, 34.0, 200.0))  # 6° down: accepted
    with pytest.raises(LimitError, match=r"earlier syncs .* limits\.max_sync_deg"):
        await mount.sync_equatorial(*at(mount, 28.0, 200.0))  # another 6°: 12° in all
    state = await mount.refresh()
    assert state.alt_deg == pytest.approx(34.0, abs=0.01)
    await mount.sync_equatorial(*at(mount, 39.0, 200.0))  # back towards the truth: accepted
    assert (await mount.refresh()).alt_deg == pytest.approx(39.0, abs=0.01)


async def test_a_driver_counts_its_pc_side_syncs_against_max_sync_deg() -> None:
    """The SynScan driver keeps syncs on the PC (docs/pointing.md): the pointing model they fit
    may not move any position farther than limits.max_sync_deg. A sync near an earlier one
    replaces it. (The emulated mount behind would itself allow any sync, to test the driver.)"""
    sim = SimulatedMount(
        EQ6, site=SITE, clock=SimClock.stepped(), limits=Limits(max_sync_deg=180.0)
    )
    async with SynScanEmulator(sim) as emulator:
        host, port = await emulator.on_tcp("127.0.0.1", 0)
        mount = SynScanMount(f"tcp://{host}:{port}", site=SITE, clock=sim.now)
        await mount.connect()
        try:
            await mount.goto_horizontal(40.0, 200.0)
            sim.step(200.0)
            await mount.refresh()
            await mount.sync_equatorial(*at(sim, 35.0, 200.0))
            with pytest.raises(LimitError, match=r"limits\.max_sync_deg"):
                await mount.sync_equatorial(*at(sim, 29.0, 200.0))
            assert (await mount.refresh()).alt_deg == pytest.approx(35.0, abs=0.01)
            await mount.sync_equatorial(*at(sim, 40.0, 200.0))
            assert len(mount.pointing.syncs) == 1  # replaced the one at the same place
            assert (await mount.refresh()).alt_deg == pytest.approx(40.0, abs=0.01)
        finally:
            await mount.disconnect()


async def test_a_sync_near_the_pole_that_turns_the_ra_axis_far_is_refused() -> None:
    """1° on the sky near the pole is a long way round the RA axis: every position away from
    the pole would move that far."""
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped())
    await mount.connect()  # at home: pointing at the pole
    state = await mount.refresh()
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    target = ((state.ra_j2000_hours + 6.0) % 24.0, state.dec_j2000_deg - 1.0)
    with pytest.raises(LimitError, match="pole"):
        await mount.sync_equatorial(*target)


async def test_a_sync_while_slewing_is_refused() -> None:
    mount = await stepped_mount()
    await mount.goto_horizontal(45.0, 210.0)
    mount.step(0.5)
    here = mount.snapshot()
    assert here.slewing
    assert here.ra_j2000_hours is not None
    assert here.dec_j2000_deg is not None
    with pytest.raises(LimitError, match="slewing"):
        await mount.sync_equatorial(here.ra_j2000_hours, here.dec_j2000_deg)


def test_max_sync_deg_is_read_from_the_settings_file(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    assert parse_config("[limits]\nmax_sync_deg = 3\n", path).limits.max_sync_deg == 3.0
    assert parse_config("", path).limits.max_sync_deg == DEFAULT_MAX_SYNC_DEG
    for bad in ("0", "-1", "181", "'ten'"):
        with pytest.raises(ConfigError, match=r"limits\.max_sync_deg"):
            parse_config(f"[limits]\nmax_sync_deg = {bad}\n", path)


def test_the_docs_give_the_default_the_code_uses() -> None:
    text = (DOCS / "reliability-safety.md").read_text(encoding="utf-8")
    found = re.search(r"`limits\.max_sync_deg`[^|]*\|\s*([\d.]+)°", text)
    assert found, "docs/reliability-safety.md has no row for limits.max_sync_deg"
    assert float(found.group(1)) == DEFAULT_MAX_SYNC_DEG == Limits().max_sync_deg
    cli = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert f"max_sync_deg = {DEFAULT_MAX_SYNC_DEG:g} " in cli
