"""Meridian limits of German equatorial mounts (issue #15 part 3).

On a German mount the tube sits on one side of the pier. Tracking turns the polar axis west at
the sidereal rate, so a tube on the **west** side of the pier (looking east, ``PierSide.WEST``)
follows its target across the meridian with the counterweight rising, towards the pier; a tube
on the **east** side (looking west) moves away from the meridian. The limits, in degrees of hour
angle past the meridian:

- ``limits.meridian_west_deg``: how far west of the meridian a target may be followed with the
  tube on the west side of the pier (tracking stops there, or flips with ``limits.auto_flip``);
- ``limits.meridian_east_deg``: how far east of the meridian a target may be pointed at with the
  tube on the east side (counterweight up; tracking moves it away from this limit).

The same in both hemispheres (the pier side as :func:`scopelink.astro.destination_side_of_pier`).
A goto picks the side on which tracking lasts ``limits.min_track_minutes`` before the limit
(:func:`plan_goto_side`), and :mod:`scopelink.mount.meridian_watch` stops tracking at the limit,
or flips (a goto to the same position through the checked ``Mount.goto_equatorial``, with
tracking turned off first, so that a flip that fails leaves tracking off). Decisions, and what
each device can enforce: ``docs/meridian.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scopelink.astro import (
    SIDEREAL_RATE_DEG_S,
    PierSide,
    altaz_to_hadec,
    destination_side_of_pier,
    hour_angle_hours,
    j2000_to_apparent,
    lst_hours,
)
from scopelink.mount.errors import LimitError
from scopelink.mount.guarded import GuardedMount
from scopelink.mount.limits import Limits
from scopelink.mount.types import AlignmentMode, Capabilities, MountState, TrackingMode

__all__ = [
    "SIDE_NAMES",
    "TRACKING_DEG_PER_MIN",
    "MeridianStatus",
    "applies",
    "hour_angle_of_altaz",
    "hour_angle_of_j2000",
    "limit_of",
    "meridian_status",
    "minutes_left",
    "past_meridian_deg",
    "plan_goto_side",
    "setting_of",
    "side_problem",
]

TRACKING_DEG_PER_MIN = SIDEREAL_RATE_DEG_S * 60.0
"""How fast tracking carries the hour angle (degrees a minute, ~0.25)."""
SIDE_NAMES = {PierSide.EAST: "east", PierSide.WEST: "west", PierSide.UNKNOWN: "unknown"}


def applies(capabilities: Capabilities) -> bool:
    """Whether the meridian limits apply: German equatorial mounts only (alt-az, fork and the
    Sky Tracker have no counterweight to run into the pier)."""
    return capabilities.alignment_mode is AlignmentMode.GERMAN_POLAR


def past_meridian_deg(ha_hours: float, side: PierSide) -> float | None:
    """How far past the meridian (degrees of hour angle) the tube points on ``side``: positive
    with the counterweight up. None when the side is unknown.

    Only the meridian above the pole is judged: an hour angle more than 6 h past it counts from
    the other way round (a tube below the pole is up to 18 h of tracking short of the limit)."""
    if side is PierSide.WEST:
        return 15.0 * (ha_hours if ha_hours <= 6.0 else ha_hours - 24.0)
    if side is PierSide.EAST:
        return -15.0 * (ha_hours if ha_hours >= -6.0 else ha_hours + 24.0)
    return None


def limit_of(limits: Limits, side: PierSide) -> float:
    """The meridian limit (degrees past the meridian) of ``side``."""
    return limits.meridian_west_deg if side is PierSide.WEST else limits.meridian_east_deg


def setting_of(side: PierSide) -> str:
    return "limits.meridian_west_deg" if side is PierSide.WEST else "limits.meridian_east_deg"


def minutes_left(limits: Limits, ha_hours: float, side: PierSide) -> float | None:
    """Minutes of tracking before the tube on ``side`` reaches its meridian limit (0 at or past
    it; infinite on the east side, which tracking carries away from its limit); None when the
    side is unknown."""
    if side is PierSide.EAST:
        return math.inf
    past = past_meridian_deg(ha_hours, side)
    if past is None:
        return None
    return max(limits.meridian_west_deg - past, 0.0) / TRACKING_DEG_PER_MIN


def side_problem(limits: Limits, ha_hours: float, side: PierSide, *, tracking: bool) -> str | None:
    """Why the tube must not go to ``side`` for a target at ``ha_hours`` (past the limit, or,
    when it will track, reaching it within ``limits.min_track_minutes``), or None."""
    past = past_meridian_deg(ha_hours, side)
    if past is None:
        return None
    name, limit = SIDE_NAMES[side], limit_of(limits, side)
    if past > limit:
        return (
            f"on the {name} side of the pier it would point {past:.1f}° past the meridian, "
            f"beyond {setting_of(side)} ({limit:g}°)"
        )
    left = minutes_left(limits, ha_hours, side)
    if tracking and left is not None and left < limits.min_track_minutes:
        return (
            f"on the {name} side of the pier tracking would reach the meridian limit in "
            f"{left:.0f} min, less than limits.min_track_minutes ({limits.min_track_minutes:g})"
        )
    return None


def _other(side: PierSide) -> PierSide:
    return PierSide.EAST if side is PierSide.WEST else PierSide.WEST


def plan_goto_side(
    limits: Limits,
    ha_hours: float,
    predicted: PierSide,
    *,
    can_choose: bool,
    tracking: bool = True,
    leave: PierSide | None = None,
) -> PierSide | None:
    """The pier side a goto to a target at ``ha_hours`` must ask for, or None when the side
    the device picks by itself (``predicted``) will do.

    The device's side is kept unless it is past the limit or (``tracking``) reaches it within
    ``min_track_minutes``; then the other side, if it is no worse. Raises ``LimitError`` naming
    the setting when no side is allowed, or when another side is needed and the device cannot be
    told which (``can_choose`` False: a SynScan hand control picks its side itself). ``leave``:
    the side an automatic flip leaves, never chosen.
    """
    if predicted is PierSide.UNKNOWN:
        predicted = destination_side_of_pier(ha_hours)
    problem = side_problem(limits, ha_hours, predicted, tracking=tracking)
    if predicted is leave:
        problem = f"a meridian flip must leave the {SIDE_NAMES[predicted]} side of the pier"
    if problem is None:
        return None
    wanted = _other(predicted)
    if side_problem(limits, ha_hours, wanted, tracking=tracking) is not None:
        # Neither side tracks min_track_minutes: the one within the limits that tracks longer.
        allowed = [
            side
            for side in (predicted, wanted)
            if side is not leave and side_problem(limits, ha_hours, side, tracking=False) is None
        ]
        if not allowed:
            other = side_problem(limits, ha_hours, wanted, tracking=False)
            raise LimitError(f"the target is out of reach: {problem}; {other}: nothing was sent")
        best = max(allowed, key=lambda side: minutes_left(limits, ha_hours, side) or 0.0)
        if best is predicted:
            return None
        wanted = best
    if not can_choose:
        raise LimitError(
            f"this mount picks the pier side of a goto itself and {problem}: nothing was sent "
            "to the mount (wait until the target is past the meridian, or change the setting)"
        )
    return wanted


def hour_angle_of_j2000(
    mount: GuardedMount, ra_j2000_hours: float, dec_j2000_deg: float
) -> tuple[float, float]:
    """Hour angle (hours) and declination of date of a J2000 position at the mount's now."""
    now = mount.now()
    ra, dec = j2000_to_apparent(ra_j2000_hours, dec_j2000_deg, now)
    return hour_angle_hours(lst_hours(now, mount.site.longitude_deg), ra), dec


def hour_angle_of_altaz(mount: GuardedMount, alt_deg: float, az_deg: float) -> tuple[float, float]:
    """Hour angle (hours) and declination of an observed altitude and azimuth."""
    return altaz_to_hadec(alt_deg, az_deg, mount.site.latitude_deg)


@dataclass(frozen=True, slots=True)
class MeridianStatus:
    """Where the tube stands against its meridian limit (``minutes_left``: None while not
    tracking, infinite on the side tracking carries away from the limit)."""

    side: PierSide
    hour_angle_hours: float
    past_deg: float
    limit_deg: float
    minutes_left: float | None


def meridian_status(mount: GuardedMount, state: MountState) -> MeridianStatus | None:
    """The tube's standing against its meridian limit, or None where the limits do not apply
    or the reading lacks the pier side or the position."""
    side = state.pier_side
    ra = state.ra_of_date_hours
    if not applies(mount.capabilities) or side is PierSide.UNKNOWN or ra is None:
        return None
    tracking = state.tracking is not TrackingMode.OFF and not state.parked
    # Tracking holds RA: the hour angle grows with the clock. Standing still, the tube's hour
    # angle is the reading's.
    when = mount.now() if tracking else state.read_at
    ha = hour_angle_hours(lst_hours(when, mount.site.longitude_deg), ra)
    past = past_meridian_deg(ha, side)
    assert past is not None  # the side is known
    left = minutes_left(mount.limits, ha, side) if tracking else None
    return MeridianStatus(side, ha, past, limit_of(mount.limits, side), left)
