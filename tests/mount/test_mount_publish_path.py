"""What every published reading goes through is kept between readings, not rebuilt per poll
(the pointing model's frame): a change of what it depends on must reach the very next reading.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.astro import Site, observed_to_j2000
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
