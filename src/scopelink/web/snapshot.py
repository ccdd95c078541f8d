"""The mount as JSON for the browser: state, target, health, identity, capabilities, limits."""

from __future__ import annotations

from scopelink.astro import SIDEREAL_RATE_DEG_S
from scopelink.astro.catalog import EphemerisRangeError
from scopelink.mount import Limits, Mount, MountState, SlewTarget, TrackingMode
from scopelink.mount.meridian import meridian_status
from scopelink.mount.sun import SunZone
from scopelink.web.pad import rates_json

__all__ = ["describe_mount", "horizon_outline", "meridian_json", "state_json", "sun_json"]

_OUTLINE_STEP_DEG = 2
_SUN_WARNING_MIN = 60
"""How far ahead the dashboard warns that the Sun will reach a mount standing still."""


def _round(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


def _target_json(target: SlewTarget | None) -> dict[str, object] | None:
    if target is None:
        return None
    return {
        "name": target.name,
        "ra_j2000_hours": _round(target.ra_j2000_hours, 6),
        "dec_j2000_deg": _round(target.dec_j2000_deg, 5),
        "alt_deg": _round(target.alt_deg, 4),
        "az_deg": _round(target.az_deg, 4),
    }


def state_json(mount: Mount, state: MountState) -> dict[str, object]:
    """What the status and health panels show, and where the chart draws the mount and target."""
    target = mount.target
    target_altaz: tuple[float, float] | None = None
    if target is None:
        pass
    elif target.ra_j2000_hours is not None and target.dec_j2000_deg is not None:
        target_altaz = mount.observed_altaz(target.ra_j2000_hours, target.dec_j2000_deg)
    elif target.alt_deg is not None and target.az_deg is not None:
        target_altaz = (target.alt_deg, target.az_deg)
    poller = mount.poller
    age_s = state.position_age_s()
    return {
        "read_at": state.read_at.isoformat(),
        "connected": state.connected,
        # How old the position is, and whether it may be shown as current (the page greys it).
        "age_s": round(age_s, 1),
        "state_age_s": round(state.age_s(), 1),
        "stale_after_s": mount.stale_after_s,
        "stale": not state.connected or age_s > mount.stale_after_s,
        "ra_j2000_hours": _round(state.ra_j2000_hours, 6),
        "dec_j2000_deg": _round(state.dec_j2000_deg, 5),
        "ra_of_date_hours": _round(state.ra_of_date_hours, 6),
        "dec_of_date_deg": _round(state.dec_of_date_deg, 5),
        "alt_deg": _round(state.alt_deg, 4),
        "az_deg": _round(state.az_deg, 4),
        "pier_side": state.pier_side.name.lower(),
        "slewing": state.slewing,
        "tracking": state.tracking.value,
        "parked": state.parked,
        "aligned": state.aligned,
        "pulse_guiding": state.pulse_guiding,
        "problems": list(state.problems),
        "target": _target_json(target),
        "target_altaz": None
        if target_altaz is None
        else {"alt": round(target_altaz[0], 4), "az": round(target_altaz[1], 4)},
        "sun": sun_json(mount, state),
        "meridian": meridian_json(mount, state),
        "health": {
            "polls": poller.polls,
            "failures": poller.failures,
            "watchers": poller.watchers,
        },
    }


def sun_json(mount: Mount, state: MountState | None = None) -> dict[str, object] | None:
    """Where the Sun is now, the radius of the zone around it (0: off), and in how many minutes
    the Sun will reach where a mount standing still points (None: not within the hour), for the
    chart and the warnings; None when the mount's clock is outside the ephemeris."""
    radius = mount.limits.sun_avoidance_deg
    try:
        zone = SunZone(radius, mount.site, mount.now(), mount.capabilities.alignment_mode)
    except EphemerisRangeError:
        return None
    return {
        "alt": round(zone.alt_deg, 3),
        "az": round(zone.az_deg, 3),
        "radius_deg": radius,
        "up": zone.alt_deg > 0.0,
        "reaches_mount_in_min": _sun_reaches_in_min(zone, state),
    }


def _sun_reaches_in_min(zone: SunZone, state: MountState | None) -> int | None:
    """Minutes until the Sun's zone reaches a mount that stands still (tracking off) outside
    it, if within the hour: nothing moves it away by itself (docs/reliability-safety.md)."""
    if (
        not zone.active
        or state is None
        or state.alt_deg is None
        or state.az_deg is None
        or state.slewing
        or state.tracking is not TrackingMode.OFF
        or zone.distance_deg(state.alt_deg, state.az_deg) < zone.radius_deg
    ):
        return None
    return zone.minutes_until_reached(state.alt_deg, state.az_deg, _SUN_WARNING_MIN)


def meridian_json(mount: Mount, state: MountState) -> dict[str, object] | None:
    """The tube against its meridian limit and the time left to it (None where the limits do
    not apply: not a German mount, or the pier side or position unknown; docs/meridian.md)."""
    status = meridian_status(mount, state)
    if status is None:
        return None
    side = status.side.name.lower()
    where = f"{side} side, {status.past_deg:+.1f}° of {status.limit_deg:g}° past the meridian"
    left = status.minutes_left
    if left is None:
        text = f"not tracking ({where})"
    elif left == float("inf"):
        text = f"tracking away from the limit ({where})"
    elif left <= 0.0:
        text = f"at the limit ({where})"
    else:
        text = f"limit in {int(left) // 60} h {int(left) % 60:02d} min ({where})"
    return {
        "side": side,
        "past_deg": round(status.past_deg, 3),
        "limit_deg": status.limit_deg,
        "minutes_left": None if left is None or left == float("inf") else round(left, 1),
        "text": text,
    }


def horizon_outline(limits: Limits) -> list[list[float]]:
    """The lowest allowed altitude every few degrees of azimuth: ``[[az, alt], ...]``."""
    return [
        [float(az), round(limits.horizon_at(float(az)), 3)]
        for az in range(0, 360, _OUTLINE_STEP_DEG)
    ]


def describe_mount(mount: Mount) -> dict[str, object]:
    """What does not change while a page is open: who the mount is, what it can do, its limits
    and site."""
    identity = mount.identity
    caps = mount.capabilities
    site = mount.site
    limits = mount.limits
    return {
        "identity": {
            "protocol": identity.protocol,
            "model": identity.model,
            "firmware": identity.firmware,
            "link": identity.link,
        },
        "capabilities": {
            "alignment_mode": caps.alignment_mode.value,
            "can_goto": caps.can_goto,
            "can_sync": caps.can_sync,
            "can_park": caps.can_park,
            "can_move_axis": list(caps.can_move_axis),
            "max_axis_rate_deg_s": caps.max_axis_rate_deg_s,
            "tracking_modes": sorted(mode.value for mode in caps.tracking_modes),
            "can_set_site": caps.can_set_site,
            "can_set_time": caps.can_set_time,
        },
        "sidereal_rate_deg_s": SIDEREAL_RATE_DEG_S,  # the unit of the pad's "8x" speeds
        "rates": rates_json(mount),  # the pad's speeds, named as the hand control names them
        "site": {
            "latitude_deg": site.latitude_deg,
            "longitude_deg": site.longitude_deg,
            "elevation_m": site.elevation_m,
        },
        "limits": {
            "horizon_deg": limits.horizon_deg,
            "max_altitude_deg": limits.max_altitude_deg,
            "sun_avoidance_deg": limits.sun_avoidance_deg,
            "horizon": horizon_outline(limits),
        },
    }
