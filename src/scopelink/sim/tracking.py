"""Tracking as a function of time: where the axes must be to stay on a J2000 position.

A :class:`SkyPath` turns a target (J2000, optionally drifting in RA for lunar and solar rates)
into the two axis counters at any elapsed time, through ``astro`` (precession, nutation,
aberration, refraction, Earth rotation): the axes follow it exactly, so nothing accumulates
however long the clock runs. Evaluations are cached per time, since both axes (and the rate
estimates) ask for the same instants.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from datetime import datetime, timedelta

from scopelink.astro import PierSide, Site, j2000_to_observed
from scopelink.mount import TrackingMode
from scopelink.sim.geometry import Geometry
from scopelink.sim.models import LUNAR_RATE_DEG_S, SIDEREAL_RATE_DEG_S, SOLAR_RATE_DEG_S

__all__ = ["SkyPath", "SkyTarget", "ra_drift_hours_per_s"]

_CACHE_SIZE = 64


def ra_drift_hours_per_s(mode: TrackingMode) -> float:
    """How fast the tracked RA moves eastwards, so the axis turns at the mode's rate."""
    rate = {TrackingMode.LUNAR: LUNAR_RATE_DEG_S, TrackingMode.SOLAR: SOLAR_RATE_DEG_S}.get(
        mode, SIDEREAL_RATE_DEG_S
    )
    return (SIDEREAL_RATE_DEG_S - rate) / 15.0


@dataclass(frozen=True, slots=True)
class SkyTarget:
    """A J2000 position at elapsed time ``at_s``, drifting east by ``ra_drift_hours_per_s``."""

    ra_j2000_hours: float
    dec_j2000_deg: float
    at_s: float
    ra_drift_hours_per_s: float = 0.0

    def ra_at(self, t: float) -> float:
        return (self.ra_j2000_hours + self.ra_drift_hours_per_s * (t - self.at_s)) % 24.0


def _unwrap(value: float, reference: float) -> float:
    return reference + (value - reference + 180.0) % 360.0 - 180.0


class SkyPath:
    """The axis counters that keep the tube on ``target``, as functions of elapsed time.

    ``epoch`` is the UTC date at elapsed 0 (fixed for the life of the path); ``side`` the pier
    side on a German mount. Counters are unwrapped so they never jump: a freely turning primary
    (azimuth, fork RA) near ``primary_reference`` (the counter when the path was made, so a goto
    takes the short way round); any other counter near its own value at the target's
    ``at_s``, so a German mount reaches it without turning the counterweight up.
    """

    def __init__(
        self,
        target: SkyTarget,
        *,
        geometry: Geometry,
        site: Site,
        epoch: datetime,
        side: PierSide,
        primary_reference: float | None = None,
    ) -> None:
        self.target = target
        self.geometry = geometry
        self.site = site
        self.epoch = epoch
        self.side = side
        anchor = self._raw_axes_at(target.at_s)
        if not geometry.primary_wraps or primary_reference is None:
            primary_reference = anchor[0]
        self._reference = (primary_reference, anchor[1])
        self._cache: OrderedDict[float, tuple[float, float]] = OrderedDict()

    def observed_at(self, t: float) -> tuple[float, float]:
        """Observed (altitude, azimuth) of the target at elapsed ``t``."""
        when = self.epoch + timedelta(seconds=t)
        return j2000_to_observed(self.target.ra_at(t), self.target.dec_j2000_deg, when, self.site)

    def _raw_axes_at(self, t: float) -> tuple[float, float]:
        alt, az = self.observed_at(t)
        return self.geometry.to_axes(alt, az, self.side)

    def axes_at(self, t: float) -> tuple[float, float]:
        """Both counters at elapsed ``t``."""
        cached = self._cache.get(t)
        if cached is not None:
            return cached
        primary, secondary = self._raw_axes_at(t)
        axes = (_unwrap(primary, self._reference[0]), _unwrap(secondary, self._reference[1]))
        self._cache[t] = axes
        if len(self._cache) > _CACHE_SIZE:
            self._cache.popitem(last=False)
        return axes

    def primary(self, t: float) -> float:
        return self.axes_at(t)[0]

    def secondary(self, t: float) -> float:
        return self.axes_at(t)[1]
