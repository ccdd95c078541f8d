"""The Sky Tracker and the Sky Commander drive and read an alt-azimuth telescope only (the spec:
"slew an alt-azimuth telescope"): given an equatorial mount they refuse at construction, in one
line."""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.servers.skytracker import SkyCommanderEmulator, SkyTrackerEmulator
from scopelink.sim import AZ_GTI, EQ6, HEQ5, SimClock, SimulatedMount
from tests.support.skytracker_emulator import SITE


@pytest.mark.parametrize("emulator", [SkyTrackerEmulator, SkyCommanderEmulator])
def test_an_equatorial_mount_is_refused_and_an_alt_az_one_accepted(
    emulator: type[SkyTrackerEmulator | SkyCommanderEmulator], tmp_path: Path
) -> None:
    for model in (EQ6, HEQ5):
        mount = SimulatedMount(model, site=SITE, clock=SimClock.stepped())
        with pytest.raises(ValueError, match=r"alt-azimuth") as refusal:
            emulator(mount, tmp_path)
        assert model.name in str(refusal.value)
        assert "\n" not in str(refusal.value)
    emulator(SimulatedMount(AZ_GTI, site=SITE, clock=SimClock.stepped()), tmp_path)
