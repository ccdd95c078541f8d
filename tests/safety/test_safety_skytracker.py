"""The Sky Tracker driver on TCP to the Sky Tracker emulator (device horizon -10°): a goto below
scopelink's 10° horizon never reaches the box, and a slew down stops above it."""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.mount import LimitError, MountAxis
from scopelink.protocol.skytracker import LoadObject, SelectMode, TrackerMode
from tests.support.safety import (
    HORIZON_DEG,
    TOLERANCE_DEG,
    j2000_at,
    skytracker_rig,
    wait_until_still,
)


async def test_a_goto_below_the_horizon_never_reaches_the_box(tmp_path: Path) -> None:
    async with skytracker_rig(tmp_path) as rig:
        with pytest.raises(LimitError, match=r"below the configured horizon of 10\.00°"):
            await rig.mount.goto_equatorial(*j2000_at(rig.sim, 2.0, 200.0))
        loads = [c for c in rig.received if isinstance(c, LoadObject)]
        gotos = [c for c in rig.received if c == SelectMode(TrackerMode.GOTO)]
        assert loads == []
        assert gotos == []
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG


async def test_a_slew_down_is_stopped_above_the_horizon(tmp_path: Path) -> None:
    async with skytracker_rig(tmp_path, at=(20.0, 180.0), rate=3.0) as rig:
        await rig.mount.move_axis(MountAxis.SECONDARY, -4.0)
        rest = await wait_until_still(rig)
        assert rest < 17.0  # it did go down
        assert rig.min_alt_deg >= HORIZON_DEG - TOLERANCE_DEG, rig.min_alt_deg
        assert not rig.mount.state.slewing
