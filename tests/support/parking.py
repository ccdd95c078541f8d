"""Helpers for the park-and-resume tests (issue #15 part 2): where the emulated tube really
points, and letting a stepped simulation run until the driver has seen a goto end."""

from __future__ import annotations

from scopelink.astro import angular_separation_deg, j2000_to_observed
from scopelink.mount import MountState
from scopelink.sim import SimulatedMount
from tests.support.synscan_driver import Rig


def tube_altaz(sim: SimulatedMount) -> tuple[float, float]:
    """Where the tube physically points now (observed alt, az): the counters minus every
    redefinition (syncs, power cycles, "set axis position")."""
    t = sim.elapsed()
    primary, secondary = (axis.physical_position_at(t) for axis in sim.axes)
    return sim.geometry.to_observed(primary, secondary)


def tube_off_target_deg(sim: SimulatedMount, ra_j2000_hours: float, dec_j2000_deg: float) -> float:
    """How far (degrees) the tube physically points from a J2000 position now."""
    alt, az = tube_altaz(sim)
    target_alt, target_az = j2000_to_observed(ra_j2000_hours, dec_j2000_deg, sim.now(), sim.site)
    return float(angular_separation_deg(az, alt, target_az, target_alt))


async def settle(r: Rig, step_s: float = 2.0, limit_s: float = 900.0) -> MountState:
    """Step the simulated clock until the driver reads the mount at rest (a stepped clock)."""
    state = await r.mount.refresh()
    waited = 0.0
    while state.slewing:
        assert waited < limit_s, "the mount is still slewing"
        r.sim.step(step_s)
        waited += step_s
        state = await r.mount.refresh()
    return state
