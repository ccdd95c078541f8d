"""Tracking as a function of time: where the axes must be to stay on a J2000 position.

A :class:`SkyPath` turns a target (J2000, optionally drifting in RA for lunar and solar rates)
into the two axis counters at any elapsed time, through ``astro`` (precession, nutation,
aberration, refraction, Earth rotation): the axes follow it exactly, so nothing accumulates
however long the clock runs. Evaluations are cached per time, since both axes (and the rate
estimates) ask for the same instants.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta

from scopelink.astro import (
    SIDEREAL_RATE_DEG_S,
    PierSide,
    Site,
    j2000_to_observed,
    wrap_signed_degrees,
)
from scopelink.mount import TrackingMode
from scopelink.mount.rates import TrackingRates, tracking_rate_deg_s
from scopelink.sim.geometry import Geometry

__all__ = [
    "POLE_TRACKING_DEG",
    "PolarAxisPath",
    "SkyPath",
    "SkyTarget",
    "ra_drift_hours_per_s",
    "sky_target",
    "tracking_path",
    "tracking_rate_deg_s",
]

_CACHE_SIZE = 64

POLE_TRACKING_DEG = 0.5
"""Within this of the celestial pole, tracking turns the polar axis uniformly (PolarAxisPath)."""


def ra_drift_hours_per_s(mode: TrackingMode, custom: TrackingRates | None = None) -> float:
    """How fast the tracked RA moves eastwards, so the axis turns at the mode's rate (plus a
    custom RA rate, :mod:`scopelink.mount.rates`)."""
    extra = 0.0 if custom is None else custom.ra_hours_per_s
    return (SIDEREAL_RATE_DEG_S - tracking_rate_deg_s(mode)) / 15.0 + extra


@dataclass(frozen=True, slots=True)
class SkyTarget:
    """A J2000 position at elapsed time ``at_s``, drifting east by ``ra_drift_hours_per_s``."""

    ra_j2000_hours: float
    dec_j2000_deg: float
    at_s: float
    ra_drift_hours_per_s: float = 0.0
    dec_drift_deg_per_s: float = 0.0

    def ra_at(self, t: float) -> float:
        return (self.ra_j2000_hours + self.ra_drift_hours_per_s * (t - self.at_s)) % 24.0

    def dec_at(self, t: float) -> float:
        """The declination at ``t``, held at the pole (a custom Dec rate stops there)."""
        dec = self.dec_j2000_deg + self.dec_drift_deg_per_s * (t - self.at_s)
        return max(-90.0, min(90.0, dec))


def sky_target(
    ra_j2000_hours: float,
    dec_j2000_deg: float,
    at_s: float,
    mode: TrackingMode,
    custom: TrackingRates,
) -> SkyTarget:
    """What tracking in ``mode`` at the ``custom`` rates follows from ``at_s``."""
    drift = ra_drift_hours_per_s(mode, custom)
    return SkyTarget(ra_j2000_hours, dec_j2000_deg, at_s, drift, custom.dec_deg_per_s)


def _unwrap(value: float, reference: float) -> float:
    """``value`` plus or minus whole turns, within half a turn of ``reference``."""
    return reference + wrap_signed_degrees(value - reference)


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
        return j2000_to_observed(self.target.ra_at(t), self.target.dec_at(t), when, self.site)

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


class PolarAxisPath:
    """Tracking with the tube at the celestial pole: the polar axis turns at ``rate_deg_s`` (signed
    in counter degrees) and the declination axis holds, as a real equatorial mount tracks.

    A :class:`SkyPath` cannot be used there: the hour angle is undefined at the pole, and the sky
    point the tube sees circles the true pole (refraction lifts the view), passing through the
    polar axis, so following it exactly would need an unbounded polar-axis rate.
    """

    def __init__(self, counters: tuple[float, float], at_s: float, rate_deg_s: float) -> None:
        self.counters = counters
        self.at_s = at_s
        self.rate_deg_s = rate_deg_s

    def primary(self, t: float) -> float:
        return self.counters[0] + self.rate_deg_s * (t - self.at_s)

    def secondary(self, t: float) -> float:
        return self.counters[1]


def tracking_path(
    counters: tuple[float, float],
    t: float,
    mode: TrackingMode,
    geometry: Geometry,
    sky_path: Callable[[], SkyPath],
) -> SkyPath | PolarAxisPath:
    """Tracking in ``mode`` from ``counters`` at ``t``: uniformly about the polar axis near the
    pole (custom rates do not apply there), else the :class:`SkyPath` ``sky_path`` makes."""
    if geometry.pole_distance_deg(*counters) < POLE_TRACKING_DEG:
        return PolarAxisPath(counters, t, geometry.hemisphere * tracking_rate_deg_s(mode))
    return sky_path()
