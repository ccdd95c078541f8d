"""What every published reading goes through is kept between readings, not rebuilt per poll
(the pointing model's frame): a change of what it depends on must reach the very next reading.
"""

from __future__ import annotations

import dataclasses
from datetime import timedelta
from pathlib import Path

import pytest

from scopelink.astro import Site, observed_to_j2000
from scopelink.mount import MountState
from scopelink.mount.memory import DeviceMemory
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(48.0, 11.0)


def model_active(mount: SimulatedMount) -> bool:
    """A function, so type checkers do not narrow the property between readings."""
    return mount.pointing.active


async def test_a_new_site_s_latitude_reaches_the_next_reading_s_correction(tmp_path: Path) -> None:
    """Synced 3° high at latitude 48°: readings are corrected; after set_site to another
    latitude the syncs no longer apply (they were taken elsewhere) and the very next reading is
    the device's own; another longitude at the same latitude keeps them."""
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped())
    mount.syncs_on_device = False
    await mount.connect()
    mount.keep_pointing_in(DeviceMemory("sim-eq6", tmp_path))
    await mount.goto_horizontal(40.0, 200.0)
    mount.step(200.0)
    await mount.sync_equatorial(*observed_to_j2000(43.0, 200.0, mount.now(), SITE))
    for _ in range(3):  # the frame is kept from reading to reading
        assert (await mount.refresh()).alt_deg == pytest.approx(43.0, abs=1e-3)

    await mount.set_site(Site(48.0, 12.5))  # the same latitude: the model still applies
    corrected = await mount.refresh()
    raw = mount.state_at(mount.elapsed())
    assert model_active(mount)
    assert corrected.alt_deg is not None
    assert raw.alt_deg is not None
    assert corrected.alt_deg - raw.alt_deg == pytest.approx(3.0, abs=0.05)

    await mount.set_site(Site(40.0, 11.0))
    moved = await mount.refresh()
    assert not model_active(mount)
    assert moved.alt_deg == pytest.approx(mount.state_at(mount.elapsed()).alt_deg, abs=1e-6)
    assert mount.state.alt_deg == moved.alt_deg


class _ModelChangedMidRefresh(SimulatedMount):
    """A refresh that publishes its reading, then sees the pointing model change (the syncs
    cleared from another task, not yet republished) before it returns: the kept correction of
    what was published is no longer the current one."""

    async def refresh(self) -> MountState:
        state = self.state_at(self.elapsed())
        self._publish(state)
        self.pointing.clear()
        return state


async def test_every_reading_is_corrected_once_and_every_change_reaches_the_next() -> None:
    """One correction per reading (the refresh returns what _publish made, not a second one),
    and what it depends on reaches the very next reading: a sync kept on the PC, its removal,
    a site elsewhere on the same latitude, a jump of the clock; a model changed between the
    publish and the refresh's return is not served from the kept correction."""
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock.stepped())
    mount.syncs_on_device = False
    await mount.connect()
    await mount.goto_horizontal(40.0, 200.0)
    mount.step(200.0)
    before = await mount.refresh()
    assert before == mount.state  # nothing to correct: the reading itself
    await mount.sync_equatorial(*observed_to_j2000(43.0, 200.0, mount.now(), SITE))
    corrected = await mount.refresh()
    assert corrected.alt_deg == pytest.approx(43.0, abs=1e-3)
    assert corrected == dataclasses.replace(mount.state, problems=corrected.problems)
    raw = mount.pointing.raw_state
    assert raw is not None
    assert raw.alt_deg == pytest.approx(40.0, abs=1e-3)  # the sync is kept on its raw reading

    mount.clock.advance(3600.0)  # a jump of the clock: the next reading is an hour on
    jumped = await mount.refresh()
    assert jumped.read_at == corrected.read_at + timedelta(hours=1)
    device = mount.state_at(mount.elapsed())
    assert jumped.alt_deg is not None
    assert device.alt_deg is not None
    assert jumped.alt_deg - device.alt_deg == pytest.approx(3.0, abs=0.05)

    await mount.set_site(Site(48.0, 30.0))  # the same latitude, 19° further east
    east = await mount.refresh()
    assert model_active(mount)
    assert east.alt_deg is not None
    assert east.az_deg is not None
    ra, _ = observed_to_j2000(east.alt_deg, east.az_deg, east.read_at, Site(48.0, 30.0))
    assert east.ra_j2000_hours == pytest.approx(ra, abs=1e-9)  # the new site's, not the old

    mount.pointing.clear()
    mount.pointing_changed()
    cleared = await mount.refresh()
    assert cleared.alt_deg == pytest.approx(mount.state_at(mount.elapsed()).alt_deg, abs=1e-9)

    changing = _ModelChangedMidRefresh(EQ6, site=SITE, clock=SimClock.stepped())
    changing.syncs_on_device = False
    await changing.connect()
    await changing.goto_horizontal(40.0, 200.0)
    changing.step(200.0)
    await changing.sync_equatorial(*observed_to_j2000(43.0, 200.0, changing.now(), SITE))
    returned = await changing.refresh()  # published corrected, then the model was cleared
    assert changing.state.alt_deg == pytest.approx(43.0, abs=1e-3)
    assert returned.alt_deg == pytest.approx(40.0, abs=1e-3)
