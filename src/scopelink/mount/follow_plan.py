"""Which part of a satellite's pass a mount can follow, decided before anything moves.

A pass needs RA and Dec rates the mount may not have: the ISS near culmination crosses up to
~1°/s of sky, and its RA rate (a coordinate rate, divided by cos Dec) grows without bound near
the celestial pole. The pass is sampled every second from its rise (or now) to its set; a
second is *followable* when both rates lie within ``RATE_MARGIN`` of the mount's
``max_tracking_offset_arcsec_s`` (room for the follower's corrections) and the satellite is
inside the limits (horizon, horizon profile, maximum altitude) and outside the Sun avoidance
zone (a daytime pass may cross the Sun).

Decision (docs/tracking.md, "The follower"): the follower takes the longest followable stretch
of the pass. A pass followable throughout is followed whole; a pass the rates allow only in
part is followed in its longest part, saying which part is skipped and why; a stretch shorter
than ``MIN_FOLLOW_S`` is refused before anything moves, saying why.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

import numpy as np

from scopelink.astro import angular_separation_deg, j2000_to_observed
from scopelink.astro.targets import SatelliteTarget, next_pass, times_after, utc_datetime
from scopelink.mount.errors import LimitError, MountError
from scopelink.mount.limits import Limits
from scopelink.mount.sun import SETTING as SUN_SETTING
from scopelink.mount.sun import SunZone

__all__ = [
    "MAX_TLE_AGE_DAYS",
    "MIN_FOLLOW_S",
    "RATE_MARGIN",
    "FollowError",
    "PassPlan",
    "plan_pass",
]

RATE_MARGIN = 0.9
"""The share of the mount's largest rate a pass may need (the rest is for corrections)."""

MIN_FOLLOW_S = 30.0
"""A followable stretch shorter than this is refused: not worth a goto."""

PASS_WINDOW_HOURS = 24.0
"""How far ahead the next pass is looked for."""

MAX_TLE_AGE_DAYS = 30.0
"""A TLE further than this from the pass (before or after its epoch) is refused: SGP4 still
answers, but a low orbit's place drifts by kilometres a day (the ISS: 1-3 km, so a 30-day-old
TLE may be off by a minute along its track): the mount would follow a satellite that is not
there."""


class FollowError(MountError):
    """The target cannot be followed on this mount (the message says why); nothing moved."""


@dataclass(frozen=True, slots=True)
class PassPlan:
    """The stretch of a pass the follower takes: ``start`` to ``end`` (aware UTC); ``note`` says
    what is skipped and why (None when the whole pass is followed)."""

    start: datetime
    end: datetime
    rise: datetime
    set: datetime
    max_alt_deg: float
    peak_ra_rate_arcsec_s: float
    peak_dec_rate_arcsec_s: float
    note: str | None


def _clock(t: datetime) -> str:
    return t.strftime("%H:%M:%S UTC")


def plan_pass(
    target: SatelliteTarget,
    limits: Limits,
    max_rate_arcsec_s: float,
    now: datetime,
    sun: SunZone | None = None,
) -> PassPlan:
    """The stretch of the next pass to follow, or :class:`FollowError` saying why none;
    ``sun``: the Sun avoidance zone (None: off), whose seconds are never followed."""
    horizon = max(limits.horizon_deg, 0.0)
    satrec = target.tle.satrec
    epoch = utc_datetime(float(satrec.jdsatepoch), float(satrec.jdsatepochF))
    age_days = (now - epoch).total_seconds() / 86400.0
    if abs(age_days) > MAX_TLE_AGE_DAYS:
        raise FollowError(
            f"the TLE of {target.name} is for {epoch:%Y-%m-%d}, {abs(age_days):.0f} days "
            f"{'before' if age_days > 0 else 'after'} now: more than {MAX_TLE_AGE_DAYS:g} days "
            "from its epoch SGP4 places a low satellite far from where it is (get a recent TLE)"
        )
    found = next_pass(target, now, window_hours=PASS_WINDOW_HOURS, horizon_deg=horizon)
    if found is None:
        raise FollowError(
            f"{target.name} does not pass above the {horizon:g}° horizon in the next "
            f"{PASS_WINDOW_HOURS:g} hours (or its TLE is stale)"
        )
    begin = max(found.rise, now)
    seconds = max(1, int((found.set - begin).total_seconds()))
    offsets = np.arange(0.0, seconds + 1.0)
    jd = times_after(begin, offsets)
    ra, dec = target.positions(jd)
    ra_rate = np.gradient(np.unwrap(np.radians(ra * 15.0)), offsets) * (180.0 / np.pi) * 3600.0
    dec_rate = np.gradient(dec, offsets) * 3600.0
    alt, az = (np.atleast_1d(v) for v in j2000_to_observed(ra, dec, jd, target.site))
    inside = np.array([_inside(limits, float(a), float(z)) for a, z in zip(alt, az, strict=True)])
    in_sun = np.zeros_like(inside)
    if sun is not None and sun.active:  # the Sun moves < 0.01° against the stars in a pass
        apart = angular_separation_deg(ra * 15.0, dec, sun.ra_j2000_hours * 15.0, sun.dec_j2000_deg)
        in_sun = np.asarray(apart) < sun.radius_deg
        inside &= ~in_sun
    allowed = RATE_MARGIN * max_rate_arcsec_s
    slow_enough = (np.abs(ra_rate) <= allowed) & (np.abs(dec_rate) <= allowed)
    start, length = _longest_run(slow_enough & inside)

    def when(index: int) -> datetime:
        return utc_datetime(float(jd[0][index]), float(jd[1][index]))

    too_fast = np.flatnonzero(~slow_enough & inside)
    why = ""
    if too_fast.size:
        i = int(too_fast[0])
        axis, rate = ("RA", ra_rate[i]) if abs(ra_rate[i]) > allowed else ("Dec", dec_rate[i])
        why = (
            f"{target.name} needs {abs(rate) / 3600.0:.2f}°/s in {axis} at {_clock(when(i))}; "
            f"this mount's largest rate is {max_rate_arcsec_s / 3600.0:g}°/s "
            f"({RATE_MARGIN:.0%} of it is used, the rest is for corrections)"
        )
    if not why and in_sun.any():
        assert sun is not None
        why = (
            f"{target.name} passes within {sun.radius_deg:g}° of the Sun at "
            f"{_clock(when(int(np.flatnonzero(in_sun)[0])))} (the Sun avoidance zone, "
            f"{SUN_SETTING})"
        )
    if length < MIN_FOLLOW_S:
        reason = why or f"{target.name} stays outside the configured limits on this pass"
        raise FollowError(
            f"cannot follow the pass of {_clock(found.rise)}-{_clock(found.set)} "
            f"(culmination {found.max_alt_deg:.0f}°): {reason}"
        )
    first, last = start, start + length - 1
    note = None
    if first > 0 or last < len(offsets) - 1:
        note = f"following {_clock(when(first))}-{_clock(when(last))} of the pass only" + (
            f": {why}" if why else ": the rest is outside the configured limits"
        )
        if why and in_sun.any() and "Sun" not in why:
            assert sun is not None
            note += f"; it passes within {sun.radius_deg:g}° of the Sun ({SUN_SETTING})"
    return PassPlan(
        start=when(first),
        end=when(last),
        rise=found.rise,
        set=found.set,
        max_alt_deg=found.max_alt_deg,
        peak_ra_rate_arcsec_s=float(np.abs(ra_rate[first : last + 1]).max()),
        peak_dec_rate_arcsec_s=float(np.abs(dec_rate[first : last + 1]).max()),
        note=note,
    )


def _inside(limits: Limits, alt_deg: float, az_deg: float) -> bool:
    try:
        limits.check_altaz(alt_deg, az_deg)
    except LimitError:
        return False
    return True


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    """Start index and length of the longest run of True (0, 0 when none)."""
    best, best_start, run_start = 0, 0, None
    for i, value in enumerate([*mask.tolist(), False]):
        if value and run_start is None:
            run_start = i
        elif not value and run_start is not None:
            if i - run_start > best:
                best, best_start = i - run_start, run_start
            run_start = None
    return best_start, best
