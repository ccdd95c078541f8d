"""The soak's meridian check in the device's own sky (``bench/soak/device_sky.py``): it reads the
emulated mount's physical axes, so it sees a tube standing past its limit, however serve's clock
judges it, and not one inside it (docs/reliability-soak.md, "Meridian limits in the soak")."""

from __future__ import annotations

import pytest
from bench.soak import device_sky
from bench.soak.config import DEVICE_MERIDIAN_TOLERANCE_DEG, SITE

from scopelink.astro import PierSide
from scopelink.mount import Limits
from scopelink.sim import EQ6, SimClock, SimulatedMount
from scopelink.sim.geometry import GermanEquatorialGeometry


@pytest.mark.parametrize(
    ("side", "ha_deg", "excess_deg"),
    [
        (PierSide.WEST, 12.0, 7.0),  # counterweight up, 7° beyond the 5° west limit: fails
        (PierSide.WEST, 4.0, -1.0),  # tracking may carry it 1° further: passes
        (PierSide.EAST, -8.0, 3.0),  # 8° east of the meridian on the east side: fails
        (PierSide.EAST, 30.0, -35.0),  # the usual side for a western target
    ],
)
def test_the_device_sky_check_reads_the_tube_on_its_axes(
    side: PierSide, ha_deg: float, excess_deg: float
) -> None:
    geometry = GermanEquatorialGeometry(SITE.latitude_deg)
    home = geometry.from_hadec(ha_deg / 15.0, 40.0, side)
    mount = SimulatedMount(EQ6, site=SITE, clock=SimClock(rate=100.0), limits=Limits(), home=home)
    record = device_sky.DeviceMeridian()
    device_sky.sample(mount, record)
    assert record.samples == 1
    assert record.worst_excess_deg == pytest.approx(excess_deg, abs=0.01)
    failed = record.worst_excess_deg > DEVICE_MERIDIAN_TOLERANCE_DEG
    assert failed is (excess_deg > 0), record.worst
    assert f"on the {side.name.lower()} side (limit 5°)" in record.worst
    samples, excess, worst = device_sky.parse(record.line())
    assert (samples, worst) == (1, record.worst)
    assert excess == pytest.approx(record.worst_excess_deg, abs=1e-4)
