"""The horizon guard's judgement of what it sees: whether a motion may start, whether the mount
is near a limit, and whether the last two readings head across one (issue #11).

Pure functions of a :class:`~scopelink.mount.guarded.GuardedMount`'s limits, site and astrometry,
the guard's settings and the readings; what the mount may do *unseen* between readings is
:mod:`scopelink.mount.budget`'s. Decisions and measured margins: ``docs/reliability-safety.md``.
"""

from __future__ import annotations

import math

from scopelink.astro import altaz_to_hadec, wrap_signed_degrees
from scopelink.mount.budget import FLAT_SLOPE, Reading, altitude_slope, has_ceiling
from scopelink.mount.errors import LimitError
from scopelink.mount.guarded import GuardedMount, GuardSettings
from scopelink.mount.meridian import SIDE_NAMES, applies, limit_of, past_meridian_deg, setting_of
from scopelink.mount.sun import SETTING as SUN_SETTING
from scopelink.mount.types import AlignmentMode, MountAxis, MountState

__all__ = ["altitude_direction", "check_move", "near_limit", "reading_danger"]


def check_move(
    mount: GuardedMount,
    settings: GuardSettings,
    axis: MountAxis,
    rate_deg_s: float,
    state: MountState,
) -> None:
    """Refuse (``LimitError``) a rate motion that starts at or beyond a limit and heads further
    out, where the direction is known (see :func:`altitude_direction`)."""
    if rate_deg_s == 0.0 or state.alt_deg is None or state.az_deg is None:
        return
    limits = mount.limits
    margin = settings.margin_deg
    floor = limits.horizon_at(state.az_deg)
    at_floor = state.alt_deg <= floor + margin
    at_top = has_ceiling(limits) and state.alt_deg >= limits.max_altitude_deg - margin
    if not (at_floor or at_top):
        return
    direction = altitude_direction(mount, axis, rate_deg_s, state)
    if direction is None:
        return  # the guard judges the motion from its first readings instead
    if direction < 0.0 and at_floor:
        raise LimitError(
            f"the mount is at altitude {state.alt_deg:.2f}°, at the configured horizon of "
            f"{floor:.2f}°, and this motion would take it lower: nothing was sent to the "
            "mount (move the other way)"
        )
    if direction > 0.0 and at_top:
        raise LimitError(
            f"the mount is at altitude {state.alt_deg:.2f}°, at the configured limit of "
            f"{limits.max_altitude_deg:.2f}°, and this motion would take it higher: nothing "
            "was sent to the mount (move the other way)"
        )


def altitude_direction(
    mount: GuardedMount, axis: MountAxis, rate_deg_s: float, state: MountState
) -> float | None:
    """Whether turning ``axis`` at ``rate_deg_s`` raises (+1) or lowers (-1) the tube now; None
    where that cannot be told (conventions: :func:`scopelink.mount.budget.altitude_slope`)."""
    if mount.capabilities.alignment_mode is AlignmentMode.ALT_AZ:
        if axis is MountAxis.SECONDARY:
            return math.copysign(1.0, rate_deg_s)
        return None
    slope = altitude_slope(mount, axis, rate_deg_s, state)
    if slope is None or abs(slope) < FLAT_SLOPE:
        return None
    return math.copysign(1.0, slope)


def tracked_altitude(mount: GuardedMount, state: MountState) -> float | None:
    """Where tracking has carried the last reading's sky position by now (tracking holds RA/Dec
    fixed, so this costs astrometry only, no exchange with the device)."""
    if state.ra_j2000_hours is None or state.dec_j2000_deg is None:
        return state.alt_deg
    alt, _ = mount.observed_altaz(state.ra_j2000_hours, state.dec_j2000_deg)
    return alt


def near_limit(
    mount: GuardedMount, settings: GuardSettings, state: MountState, *, factor: float = 1.0
) -> bool:
    """Whether tracking may reach a limit soon: within ``factor`` × ``near_deg`` (plus the
    margin) of it, or of the Sun avoidance zone (or its position unknown)."""
    alt = tracked_altitude(mount, state)
    if alt is None or state.az_deg is None:
        return True
    limits = mount.limits
    near = settings.margin_deg + factor * settings.near_deg
    if _near_sun(mount, state, near):
        return True
    if alt - limits.horizon_at(state.az_deg) < near:
        return True
    return has_ceiling(limits) and limits.max_altitude_deg - alt < near


def reading_danger(
    mount: GuardedMount,
    settings: GuardSettings,
    rates: dict[MountAxis, float],
    readings: tuple[Reading, Reading],
    *,
    period_s: float,
    state: MountState,
) -> str | None:
    """Why the mount must stop now, judged from the last two ``readings`` (the poll period being
    ``period_s``) with the rate motions ``rates`` running, or None while it stays inside."""
    previous, reading = readings
    elapsed = reading.at_s - previous.at_s
    alt_rate = (reading.alt_deg - previous.alt_deg) / elapsed
    az_rate = wrap_signed_degrees(reading.az_deg - previous.az_deg) / elapsed
    ahead_s = max(settings.min_lookahead_s, settings.reaction_polls * period_s)
    # Braking from the fastest axis rate takes axis_rate / deceleration seconds, during which
    # the altitude keeps changing at about half its present rate.
    axis_rate = max((abs(rate) for rate in rates.values()), default=0.0)
    ahead_s += axis_rate / settings.braking_deg_s2 / 2.0
    alt_then = reading.alt_deg + alt_rate * ahead_s
    az_then = reading.az_deg + az_rate * ahead_s
    limits = mount.limits
    floor_now = limits.horizon_at(reading.az_deg)
    floor_then = limits.horizon_at(az_then)
    above_now = reading.alt_deg - floor_now
    above_then = alt_then - floor_then
    what = "a manual motion" if rates else f"{state.tracking.value} tracking"
    if above_then < settings.margin_deg and above_then < above_now:
        return (
            f"{what} was stopped at altitude {reading.alt_deg:.2f}° (azimuth "
            f"{reading.az_deg % 360.0:.1f}°): it was heading below the configured horizon of "
            f"{floor_then:.2f}°"
        )
    below_now = limits.max_altitude_deg - reading.alt_deg
    below_then = limits.max_altitude_deg - alt_then
    if has_ceiling(limits) and below_then < settings.margin_deg and below_then < below_now:
        return (
            f"{what} was stopped at altitude {reading.alt_deg:.2f}°: it was heading above "
            f"the configured limit of {limits.max_altitude_deg:.2f}°"
        )
    if rates:  # tracking towards the meridian limit is the meridian watch's
        reason = _meridian_danger(mount, settings, readings, ahead_s=ahead_s, state=state)
        if reason is not None:
            return reason
    # Tracking closes in at most 0.5°/h (a thin Moon): the margin is for rate motions only, so
    # a target a goto was allowed to (at the zone's edge) stays tracked.
    sun_margin = settings.margin_deg if rates else 0.0
    return _sun_danger(
        mount, reading, (alt_then, az_then), ahead_s=ahead_s, what=what, margin_deg=sun_margin
    )


_POLE_DEC_DEG = 80.0
"""Nearer the pole than this the hour angle of a reading says too little to judge the meridian."""


def _meridian_danger(
    mount: GuardedMount,
    settings: GuardSettings,
    readings: tuple[Reading, Reading],
    *,
    ahead_s: float,
    state: MountState,
) -> str | None:
    """Why a rate motion heading past the meridian limit of a German mount must stop now (the
    hour angle of the last two readings, extrapolated ``ahead_s``), or None (docs/meridian.md)."""
    side = state.pier_side
    if not applies(mount.capabilities):
        return None
    latitude = mount.site.latitude_deg
    pasts = []
    for reading in readings:
        ha, dec = altaz_to_hadec(reading.alt_deg, reading.az_deg, latitude)
        past = past_meridian_deg(ha, side)
        if past is None or abs(dec) > _POLE_DEC_DEG:
            return None
        pasts.append(past)
    (previous, reading), (past_before, past_now) = readings, pasts
    ahead = past_now + (past_now - past_before) / (reading.at_s - previous.at_s) * ahead_s
    limit = limit_of(mount.limits, side)
    if ahead < limit - settings.margin_deg or ahead <= past_now:
        return None
    return (
        f"a manual motion was stopped {past_now:.1f}° past the meridian on the "
        f"{SIDE_NAMES[side]} side of the pier: it was heading past the meridian limit "
        f"({setting_of(side)} {limit:g}°)"
    )


def _sun_danger(
    mount: GuardedMount,
    reading: Reading,
    then: tuple[float, float],
    *,
    ahead_s: float,
    what: str,
    margin_deg: float,
) -> str | None:
    """Why a motion heading into the Sun avoidance zone must stop now (the predicted altitude
    and azimuth ``then``, judged against where the Sun will be then), or None."""
    try:
        zone = mount.sun_zone()
    except LimitError as error:  # the Sun cannot be placed: nothing can be judged safe
        return f"{what} was stopped: {error}"
    if zone is None:
        return None
    now = zone.distance_deg(reading.alt_deg, reading.az_deg)
    later = zone.distance_deg(*then, later_s=ahead_s)
    if later < zone.radius_deg + margin_deg and later < now:
        return (
            f"{what} was stopped at altitude {reading.alt_deg:.2f}° (azimuth "
            f"{reading.az_deg % 360.0:.1f}°), {now:.1f}° from the Sun: it was heading into "
            f"the {zone.radius_deg:g}° Sun avoidance zone ({SUN_SETTING})"
        )
    return None


def _near_sun(mount: GuardedMount, state: MountState, near_deg: float) -> bool:
    """Whether the tracked position is within ``near_deg`` of the Sun avoidance zone."""
    if state.ra_j2000_hours is None or state.dec_j2000_deg is None:
        return False
    try:
        zone = mount.sun_zone()
    except LimitError:
        return True
    if zone is None:
        return False
    distance = zone.distance_j2000_deg(state.ra_j2000_hours, state.dec_j2000_deg)
    return distance < zone.radius_deg + near_deg
