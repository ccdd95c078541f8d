"""A satellite's pass over the site: rise, culmination and set.

The geometric altitude is sampled every ``SAMPLE_STEP_S`` over the window; each crossing of the
horizon altitude is refined by bisection to 0.01 s and the culmination by a golden-section search
of the highest point. A pass shorter than the sample step (a satellite grazing the horizon) may
be missed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime

import numpy as np

from scopelink.astro.targets.base import times_after, utc_datetime
from scopelink.astro.targets.satellite import SatelliteTarget

__all__ = ["SAMPLE_STEP_S", "SatellitePass", "next_pass"]

SAMPLE_STEP_S = 10.0
"""The altitude sampling step (a low satellite crosses ~0.5° of altitude a second at most)."""

_BISECTIONS = 10  # 10 s / 2**10 = 0.01 s


@dataclass(frozen=True, slots=True)
class SatellitePass:
    """One pass: when it rises above, culminates and sets below ``horizon_deg`` (geometric);
    ``rise`` is ``start`` when the satellite was already up then."""

    rise: datetime
    culmination: datetime
    set: datetime
    max_alt_deg: float
    horizon_deg: float

    @property
    def duration_s(self) -> float:
        return (self.set - self.rise).total_seconds()


def next_pass(
    target: SatelliteTarget,
    start: datetime,
    *,
    window_hours: float = 24.0,
    horizon_deg: float = 0.0,
) -> SatellitePass | None:
    """The first pass above ``horizon_deg`` ending after ``start`` within the window, or None."""
    offsets = np.arange(0.0, window_hours * 3600.0 + SAMPLE_STEP_S, SAMPLE_STEP_S)
    alt = target.altaz(times_after(start, offsets))[0] - horizon_deg
    above = alt > 0.0
    if not above.any():
        return None
    first = int(np.argmax(above))
    below_after = np.flatnonzero(~above[first:])
    if below_after.size == 0:
        return None  # still up at the end of the window: no set in it
    last = first + int(below_after[0]) - 1

    def altitude(seconds: float) -> float:
        return float(target.altaz(times_after(start, np.array([seconds])))[0][0]) - horizon_deg

    rise_s = 0.0 if first == 0 else _crossing(altitude, offsets[first - 1], offsets[first])
    set_s = _crossing(altitude, offsets[last + 1], offsets[last])
    peak_s = _highest(altitude, max(rise_s, offsets[first] - SAMPLE_STEP_S), set_s)
    jd1, jd2 = times_after(start, np.array([rise_s, peak_s, set_s]))
    rise, peak, end = (utc_datetime(float(a), float(b)) for a, b in zip(jd1, jd2, strict=True))
    return SatellitePass(rise, peak, end, altitude(peak_s) + horizon_deg, horizon_deg)


def _crossing(altitude: Callable[[float], float], below_s: float, above_s: float) -> float:
    """Bisection between a time below the horizon and one above it."""
    for _ in range(_BISECTIONS):
        middle = 0.5 * (below_s + above_s)
        if altitude(middle) > 0.0:
            above_s = middle
        else:
            below_s = middle
    return 0.5 * (below_s + above_s)


def _highest(altitude: Callable[[float], float], low_s: float, high_s: float) -> float:
    """Golden-section search of the highest point (the altitude has one peak in a pass)."""
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    a, b = low_s, high_s
    while b - a > 0.05:
        c, d = b - ratio * (b - a), a + ratio * (b - a)
        if altitude(c) > altitude(d):
            b = d
        else:
            a = c
    return 0.5 * (a + b)
