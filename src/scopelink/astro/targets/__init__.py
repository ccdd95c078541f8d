"""Moving targets: the Sun, Moon and planets (DE421), comets and asteroids from orbital elements
(PyEphem), Earth satellites from a TLE (SGP4), each with its J2000-equivalent place and rates at
any instant for a site, and a satellite's pass. See ``docs/tracking.md``, "Targets".
"""

from scopelink.astro.targets.base import (
    MovingTarget,
    TargetError,
    TargetKind,
    TargetRates,
    times_after,
    utc_datetime,
)
from scopelink.astro.targets.elements import OrbitTarget, orbit_target, read_orbits
from scopelink.astro.targets.passes import SatellitePass, next_pass
from scopelink.astro.targets.satellite import SatelliteTarget, Tle, read_tles, satellite_target
from scopelink.astro.targets.solar import SolarSystemTarget, solar_system_target

__all__ = [
    "MovingTarget",
    "OrbitTarget",
    "SatellitePass",
    "SatelliteTarget",
    "SolarSystemTarget",
    "TargetError",
    "TargetKind",
    "TargetRates",
    "Tle",
    "next_pass",
    "orbit_target",
    "read_orbits",
    "read_tles",
    "satellite_target",
    "solar_system_target",
    "times_after",
    "utc_datetime",
]
