"""The horizon guard's arithmetic for what a mount may do while nobody sees it (issue #11).

Between good readings (a noisy link, a lost reply, a resynchronisation) the guard budgets for the
travel it cannot see: each rate motion turns its axis at its commanded speed for the time since
the last good reading (or since its command, if later) plus the stop's latency, then brakes. How
much altitude one degree of axis travel moves is the axis's *slope* at the reading; on an
equatorial mount it drifts as the tube moves. Decisions and figures: ``docs/reliability-safety.md``
(Noisy links).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime

from scopelink.mount.errors import LimitError
from scopelink.mount.guarded import GuardedMount, GuardSettings
from scopelink.mount.limits import Limits
from scopelink.mount.sun import SETTING as SUN_SETTING
from scopelink.mount.types import AlignmentMode, MountAxis, MountState, PierSide, TrackingMode

__all__ = [
    "FLAT_SLOPE",
    "Base",
    "Reading",
    "Travel",
    "Unseen",
    "altitude_slope",
    "base_from",
    "blind_danger",
    "has_ceiling",
    "heads_out",
    "highest_floor",
    "make_base",
    "unseen_travel",
]

STEP_DEG = 0.01
"""Finite-difference step of the altitude slopes: far above rounding, far below curvature."""
FLAT_SLOPE = 1e-6 / STEP_DEG
"""A slope below this moves no altitude that can be told (the polar axis on the meridian)."""
PROFILE_STEP_DEG = 0.5
"""Azimuth step at which a horizon profile is searched for its highest point."""


@dataclass(frozen=True, slots=True)
class Reading:
    """The part of a state the guard judges, with its time on the mount's clock (seconds since
    the watch began)."""

    at_s: float
    alt_deg: float
    az_deg: float

    def same_place(self, other: Reading) -> bool:
        return self.alt_deg == other.alt_deg and self.az_deg == other.az_deg


@dataclass(frozen=True, slots=True)
class Base:
    """The last good reading, and each rate motion's altitude slope there (None: unknown)."""

    reading: Reading
    slopes: dict[MountAxis, float | None]
    rates: dict[MountAxis, float]
    """The rate motions the slopes are for."""


@dataclass(frozen=True, slots=True)
class Unseen:
    """One rate motion as the budget sees it."""

    axis: MountAxis
    speed_deg_s: float
    moving_s: float
    """How long it may have turned unseen, the stop's latency included."""


@dataclass(frozen=True, slots=True)
class Travel:
    """The worst unseen travel of the rate motions, braking included."""

    fall_deg: float
    rise_deg: float
    longest_s: float
    """The longest an axis may turn before it has stopped (unseen time and braking)."""
    az_speed_deg_s: float
    """The fastest the azimuth may change meanwhile."""


def altitude_slope(
    mount: GuardedMount, axis: MountAxis, rate_deg_s: float, state: MountState
) -> float | None:
    """Degrees of altitude per degree that ``axis`` turns in the direction of ``rate_deg_s``, at
    the reading ``state`` (None where that cannot be told).

    Alt-az: the secondary axis is the altitude (positive is up); the azimuth axis moves none.
    Equatorial: the primary axis forwards turns westwards (hour angle up) in the north and
    eastwards in the south; the secondary forwards moves north in the north and south in the
    south, the other way when a German mount is flipped (an unknown pier side cannot be told).
    The slope comes from the reading's J2000 position through the same astrometry as everything
    else (a finite difference of ``STEP_DEG``).
    """
    mode = mount.capabilities.alignment_mode
    if mode is AlignmentMode.ALT_AZ:
        return math.copysign(1.0, rate_deg_s) if axis is MountAxis.SECONDARY else 0.0
    ra, dec, alt = state.ra_j2000_hours, state.dec_j2000_deg, state.alt_deg
    if ra is None or dec is None or alt is None:
        return None
    hemisphere = 1.0 if mount.site.latitude_deg >= 0.0 else -1.0
    step = STEP_DEG
    if axis is MountAxis.PRIMARY:
        # The hour angle grows as the right ascension under the tube falls.
        moved, _ = mount.observed_altaz((ra - step / 15.0) % 24.0, dec)
        sign = hemisphere
    else:
        normal = PierSide.EAST if hemisphere > 0.0 else PierSide.WEST
        if mode is AlignmentMode.GERMAN_POLAR and state.pier_side is PierSide.UNKNOWN:
            return None
        flipped = mode is AlignmentMode.GERMAN_POLAR and state.pier_side is not normal
        towards = step if dec + step <= 90.0 else -step
        moved, _ = mount.observed_altaz(ra, dec + towards)
        sign = hemisphere * (-1.0 if flipped else 1.0) * math.copysign(1.0, towards)
    here_alt, _ = mount.observed_altaz(ra, dec)
    return (moved - here_alt) / step * sign * math.copysign(1.0, rate_deg_s)


def make_base(
    mount: GuardedMount, rates: dict[MountAxis, float], reading: Reading, state: MountState
) -> Base:
    """A good reading and, for each rate motion, its altitude slope there."""
    slopes = {axis: altitude_slope(mount, axis, rate, state) for axis, rate in rates.items()}
    return Base(reading, slopes, dict(rates))


def base_from(
    mount: GuardedMount,
    rates: dict[MountAxis, float],
    state: MountState,
    origin: datetime,
    base: Base | None,
) -> Base | None:
    """The budget's start when no good reading came in: the last one published (its time is its
    own), or the current base's reading with the slopes of today's motions."""
    if base is not None:
        reading = base.reading
    elif state.alt_deg is not None and state.az_deg is not None:
        reading = Reading((state.read_at - origin).total_seconds(), state.alt_deg, state.az_deg)
    else:
        return None
    return make_base(mount, rates, reading, state)


def unseen_travel(
    motions: list[Unseen],
    slopes: dict[MountAxis, float | None],
    *,
    altaz: bool,
    latitude_deg: float,
    alt_deg: float,
    braking_deg_s2: float,
) -> Travel:
    """The worst altitude the rate motions may lose (``fall``) and gain (``rise``) unseen.

    Each axis turns at its speed for its ``moving_s``, then brakes at ``braking_deg_s2``. Its
    slope towards the limit starts at the reading's (an unknown one counts as the steepest, a
    slope away from the limit as nothing until it could have turned), may drift by 2x the axes'
    total speed in radians per second on an equatorial mount (none on an alt-az one, where it is
    exactly 1 or 0), and is at most cos(latitude) for the polar axis (dAlt/dHA = cos φ sin A), 1
    for the declination or altitude axis.
    """
    cos_lat = abs(math.cos(math.radians(latitude_deg)))
    total_speed = sum(motion.speed_deg_s for motion in motions)
    drift = 0.0 if altaz else 2.0 * math.radians(total_speed)
    fall = rise = longest_s = 0.0
    for motion in motions:
        speed = motion.speed_deg_s
        brake_s = speed / braking_deg_s2
        longest_s = max(longest_s, motion.moving_s + brake_s)
        if altaz and motion.axis is MountAxis.PRIMARY:
            continue  # the azimuth axis moves no altitude (the horizon profile is the floor's)
        steepest = cos_lat if motion.axis is MountAxis.PRIMARY and not altaz else 1.0
        slope = slopes.get(motion.axis)
        for sign in (-1.0, 1.0):  # towards the horizon, then towards the altitude limit
            towards = steepest if slope is None else sign * slope
            travel = worst_travel(towards, steepest, drift, motion.moving_s)
            braking = clamp(towards + drift * motion.moving_s, steepest) * speed * brake_s / 2.0
            if sign < 0.0:
                fall += speed * travel + braking
            else:
                rise += speed * travel + braking
    # The azimuth turns faster than the axes by up to 1/cos(alt) on an equatorial mount.
    az_speed = total_speed if altaz else total_speed / max(math.cos(math.radians(alt_deg)), 0.1)
    return Travel(fall, rise, longest_s, az_speed)


def heads_out(room_deg: float, travel_deg: float, tracked_deg: float) -> bool:
    """Whether unseen travel (``travel_deg`` by rate motions, ``tracked_deg`` by tracking) may
    use up ``room_deg`` (negative: beyond the limit already, where only a motion that may head
    further out counts: one heading back in must be allowed to)."""
    if room_deg <= 0.0:
        return travel_deg > 0.0
    return travel_deg + tracked_deg >= room_deg


def clamp(slope: float, steepest: float) -> float:
    return min(max(slope, 0.0), steepest)


def worst_travel(towards: float, steepest: float, drift: float, seconds: float) -> float:
    """Degrees of altitude per °/s of axis speed over ``seconds``, towards a limit: the slope
    (altitude per axis degree, positive towards the limit) starts at ``towards``, grows by at
    most ``drift`` a second and is at most ``steepest``; a slope away from the limit counts 0."""
    if drift <= 0.0:
        return clamp(towards, steepest) * seconds
    # The slope reaches 0 at t0 and the cap at t1; linear in between.
    t0 = min(max(-towards / drift, 0.0), seconds)
    t1 = min(max((steepest - towards) / drift, 0.0), seconds)
    if t1 <= t0:
        return clamp(towards, steepest) * (seconds - t0) if towards >= steepest else 0.0
    linear = towards * (t1 - t0) + drift * (t1 * t1 - t0 * t0) / 2.0
    return linear + steepest * (seconds - t1)


def highest_floor(limits: Limits, az_deg: float, span_deg: float) -> float:
    """The highest horizon within ``span_deg`` of ``az_deg`` either way."""
    if not limits.horizon_profile:
        return limits.horizon_deg
    if span_deg >= 180.0:
        return max(limits.horizon_deg, *(alt for _, alt in limits.horizon_profile))
    steps = max(2, math.ceil(2.0 * span_deg / PROFILE_STEP_DEG))
    candidates = [az_deg - span_deg + 2.0 * span_deg * i / steps for i in range(steps + 1)]
    candidates += [
        az
        for az, _ in limits.horizon_profile
        if abs((az - az_deg + 180.0) % 360.0 - 180.0) <= span_deg
    ]
    return max(limits.horizon_at(az % 360.0) for az in candidates)


def blind_danger(
    mount: GuardedMount,
    settings: GuardSettings,
    motions: list[Unseen],
    base: Base,
    *,
    now_s: float,
    state: MountState,
) -> str | None:
    """Why the mount must stop now because of what it may have done unseen since ``base``, or
    None while even the worst case stays inside the limits (the 0.2° margin included).

    The unseen travel is :func:`unseen_travel`'s; tracking adds ``tracking_deg_s``; the horizon
    is the highest it gets over the azimuths the tube could reach meanwhile.
    """
    reading = base.reading
    travel = unseen_travel(
        motions,
        base.slopes,
        altaz=mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ,
        latitude_deg=mount.site.latitude_deg,
        alt_deg=reading.alt_deg,
        braking_deg_s2=settings.braking_deg_s2,
    )
    unseen_s = now_s - reading.at_s + settings.stop_latency_s
    limits = mount.limits
    span = travel.az_speed_deg_s * max(unseen_s, travel.longest_s)
    floor = highest_floor(limits, reading.az_deg, span)
    what = "a manual motion" if motions else f"{state.tracking.value} tracking"
    blind = max(now_s - reading.at_s, 0.0)
    unseen = f"worst case after {blind:.2f} s unseen, the stop and the braking"
    tracking = state.tracking is not TrackingMode.OFF
    tracked = settings.tracking_deg_s * unseen_s if tracking else 0.0
    # Beyond a limit already, only a motion that may head further out is stopped (one that
    # heads back in must be allowed to); tracking alone is judged by the readings there.
    if heads_out(reading.alt_deg - floor - settings.margin_deg, travel.fall_deg, tracked):
        return (
            f"{what} was stopped at altitude {reading.alt_deg:.2f}° (azimuth "
            f"{reading.az_deg % 360.0:.1f}°): it was heading below the configured horizon of "
            f"{floor:.2f}° ({unseen})"
        )
    room_up = limits.max_altitude_deg - settings.margin_deg - reading.alt_deg
    if has_ceiling(limits) and heads_out(room_up, travel.rise_deg, tracked):
        return (
            f"{what} was stopped at altitude {reading.alt_deg:.2f}°: it was heading above "
            f"the configured limit of {limits.max_altitude_deg:.2f}° ({unseen})"
        )
    return _blind_sun_danger(
        mount, settings, motions, reading, unseen_s=unseen_s, what=what, unseen=unseen
    )


def sky_travel_deg(motions: list[Unseen], braking_deg_s2: float) -> float:
    """The farthest the rate motions may carry the tube across the sky unseen, braking included
    (an axis turning by an angle moves the tube by at most that angle on the sky; the axes'
    travels add up at worst)."""
    return sum(
        m.speed_deg_s * m.moving_s + m.speed_deg_s**2 / (2.0 * braking_deg_s2) for m in motions
    )


def _blind_sun_danger(
    mount: GuardedMount,
    settings: GuardSettings,
    motions: list[Unseen],
    reading: Reading,
    *,
    unseen_s: float,
    what: str,
    unseen: str,
) -> str | None:
    """Why unseen rate motions must stop before they could reach the Sun avoidance zone, or
    None. The direction of the unseen travel is not known, so any direction counts; inside the
    zone's margin already, the readings judge (a motion heading out must be allowed to)."""
    if not motions:
        return None  # tracking follows the stars: the Sun closes in at most 0.5°/h (a thin Moon)
    try:
        zone = mount.sun_zone()
    except LimitError:
        return None  # no Sun can be placed: the reading-based check stops every motion
    if zone is None:
        return None
    distance = zone.distance_deg(reading.alt_deg, reading.az_deg, later_s=unseen_s)
    room = distance - zone.radius_deg - settings.margin_deg
    if room <= 0.0 or sky_travel_deg(motions, settings.braking_deg_s2) < room:
        return None
    return (
        f"{what} was stopped at altitude {reading.alt_deg:.2f}° (azimuth "
        f"{reading.az_deg % 360.0:.1f}°), {distance:.1f}° from the Sun: it could reach the "
        f"{zone.radius_deg:g}° Sun avoidance zone ({SUN_SETTING}) ({unseen})"
    )


def has_ceiling(limits: Limits) -> bool:
    """Whether an altitude limit is set: at 90° (the default) nothing can pass it, and a star
    culminating near the zenith must not have its tracking turned off."""
    return limits.max_altitude_deg < 90.0
