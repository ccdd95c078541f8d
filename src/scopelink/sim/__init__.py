"""The simulated mount: a clock, two motor axes with exact motion, geometry, presets.

Device emulators (SynScan hand control, Sky Tracker, Sky Commander) sit on top of
:class:`SimulatedMount`. See ``docs/simulator.md``.
"""

from scopelink.sim.axis import Axis, Phase, Segment, Trajectory, plan_move, ramp_phase
from scopelink.sim.clock import DEFAULT_EPOCH, SimClock
from scopelink.sim.geometry import (
    AltAzimuthGeometry,
    ForkEquatorialGeometry,
    Geometry,
    GermanEquatorialGeometry,
    geometry_for,
)
from scopelink.sim.limit_search import LimitStop
from scopelink.sim.misalignment import Misalignment
from scopelink.sim.models import (
    AZ_GTI,
    DOB_GOTO,
    EQ6,
    HEQ5,
    PRESETS,
    SKY_TRACKER,
    SYNSCAN_FIXED_RATE_MULTIPLES,
    SYNSCAN_FIXED_RATES_DEG_S,
    MountModel,
    synscan_fixed_rate_deg_s,
)
from scopelink.sim.mount import SimulatedMount
from scopelink.sim.tracking import SkyPath, SkyTarget, ra_drift_hours_per_s

__all__ = [
    "AZ_GTI",
    "DEFAULT_EPOCH",
    "DOB_GOTO",
    "EQ6",
    "HEQ5",
    "PRESETS",
    "SKY_TRACKER",
    "SYNSCAN_FIXED_RATES_DEG_S",
    "SYNSCAN_FIXED_RATE_MULTIPLES",
    "AltAzimuthGeometry",
    "Axis",
    "ForkEquatorialGeometry",
    "Geometry",
    "GermanEquatorialGeometry",
    "LimitStop",
    "Misalignment",
    "MountModel",
    "Phase",
    "Segment",
    "SimClock",
    "SimulatedMount",
    "SkyPath",
    "SkyTarget",
    "Trajectory",
    "geometry_for",
    "plan_move",
    "ra_drift_hours_per_s",
    "ramp_phase",
    "synscan_fixed_rate_deg_s",
]
