"""Which way a rate motion moves the altitude, as the guard tells it, against the simulator's exact
geometry: both hemispheres, both sides of the pier, alt-az and German equatorial."""

from __future__ import annotations

from datetime import UTC, datetime

import pytest

from scopelink.astro import Site
from scopelink.mount import MountAxis
from scopelink.sim import AZ_GTI, EQ6, MountModel, SimClock, SimulatedMount

START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)
SITES = {"north": Site(48.0, 11.0, pressure_hpa=0.0), "south": Site(-33.9, 18.4, pressure_hpa=0.0)}


@pytest.mark.parametrize("model", [EQ6, AZ_GTI], ids=lambda m: m.name)
@pytest.mark.parametrize("hemisphere", sorted(SITES))
@pytest.mark.parametrize("az_deg", [60.0, 160.0, 200.0, 300.0])
@pytest.mark.parametrize("axis", list(MountAxis))
async def test_the_told_direction_is_the_one_the_mount_moves(
    model: MountModel, hemisphere: str, az_deg: float, axis: MountAxis
) -> None:
    sim = SimulatedMount(model, site=SITES[hemisphere], clock=SimClock.stepped(START))
    await sim.connect()
    await sim.goto_horizontal(30.0, az_deg)
    sim.step(300.0)  # landed
    state = sim.snapshot()
    for rate in (1.0, -1.0):
        told = sim.guard.altitude_direction(axis, rate, state)
        await sim.move_axis(axis, rate)
        moved = sim.step(0.5).alt_deg
        await sim.move_axis(axis, 0.0)
        back = sim.step(5.0)
        assert moved is not None
        assert state.alt_deg is not None
        # Only an alt-az mount's azimuth axis moves no altitude; everything else can be told.
        assert (told is None) == (model is AZ_GTI and axis is MountAxis.PRIMARY)
        if told is not None:
            change = moved - state.alt_deg
            assert abs(change) > 1e-3, (told, change)
            assert told == (1.0 if change > 0 else -1.0), (state.pier_side, rate, change)
        state = back  # the next rate starts from where this one stopped
