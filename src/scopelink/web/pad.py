"""The direction pad: which axis and sign each arrow moves, and the rates named as the hand control
names them (``docs/dashboard.md``, "Controls").

Directions follow the sky, not the axes. On an equatorial mount the arrows are N, S, E and W:
north moves the tube towards the celestial pole of the northern sky (declination up), east towards
increasing right ascension. Which axis sign that is depends on the hemisphere and, on a German
mount, on the pier side (the conventions of :func:`scopelink.mount.budget.altitude_slope`): the
mapping is sent with every state, so a meridian flip turns the buttons with the tube. With the
pier side unknown the secondary axis cannot be named north or south: the pad then says "Dec +" and
"Dec −". On an alt-azimuth mount the arrows are Up, Down, Left and Right as the observer sees the
tube: up raises the altitude, right increases the compass azimuth (clockwise seen from above).

Rates: a SynScan mount (or a simulator of one) gets the hand control's speed keys 1-9 with their
speeds; a Sky Tracker its three arrow speeds (GUIDE 2′/s at the box's default ``K`` speed, TRACK
8′/s, UTILITY 4°/s); any other mount multiples of the sidereal rate. Nothing above the mount's
``max_axis_rate_deg_s`` is offered.
"""

from __future__ import annotations

from scopelink.astro import SIDEREAL_RATE_DEG_S, PierSide
from scopelink.drivers.skytracker.motion import TRACK_ARROW_ARCSEC_S, UTILITY_ARROW_ARCSEC_S
from scopelink.mount import AlignmentMode, Mount, MountState
from scopelink.protocol.skytracker.messages import DEFAULT_GUIDE_SPEED_ARCSEC_PER_S
from scopelink.sim import SKY_TRACKER, SYNSCAN_FIXED_RATE_MULTIPLES, SimulatedMount

__all__ = ["DEFAULT_SYNSCAN_RATE", "GENERIC_MULTIPLES", "pad_json", "rates_json"]

GENERIC_MULTIPLES = (1.0, 8.0, 32.0, 128.0, 400.0)
"""Multiples of the sidereal rate offered by a mount with no hand-control speeds of its own."""
DEFAULT_SYNSCAN_RATE = 7
"""Rate 7 (400×): the first speed that crosses an eyepiece's field at a useful pace."""


def _hand_control(mount: Mount) -> str:
    protocol = mount.identity.protocol
    if isinstance(mount, SimulatedMount):
        if mount.model.synscan_model_code is not None:
            return "synscan"
        return "skytracker" if mount.model == SKY_TRACKER else "generic"
    return protocol if protocol in ("synscan", "skytracker") else "generic"


def _speed(rate_deg_s: float) -> str:
    if rate_deg_s >= 1.0:
        return f"{rate_deg_s:.2g}°/s" if rate_deg_s < 10 else f"{rate_deg_s:.0f}°/s"
    if rate_deg_s * 60.0 >= 1.0:
        return f"{rate_deg_s * 60.0:.3g}′/s"
    return f"{rate_deg_s * 3600.0:.3g}″/s"


def rates_json(mount: Mount) -> dict[str, object]:
    """The pad's speeds: ``{"choices": [{"key", "label", "rate_deg_s"}], "default": key}``."""
    limit = mount.capabilities.max_axis_rate_deg_s
    kind = _hand_control(mount)
    choices: list[dict[str, object]] = []
    default = ""
    if kind == "synscan":
        for number, multiple in enumerate(SYNSCAN_FIXED_RATE_MULTIPLES, start=1):
            rate = multiple * SIDEREAL_RATE_DEG_S
            label = f"rate {number} · {multiple:g}× ({_speed(rate)})"
            choices.append({"key": str(number), "label": label, "rate_deg_s": min(rate, limit)})
        default = str(DEFAULT_SYNSCAN_RATE)
    elif kind == "skytracker":
        for key, arcsec_s in (
            ("guide", float(DEFAULT_GUIDE_SPEED_ARCSEC_PER_S)),
            ("track", TRACK_ARROW_ARCSEC_S),
            ("utility", UTILITY_ARROW_ARCSEC_S),
        ):
            rate = min(arcsec_s / 3600.0, limit)
            choices.append({"key": key, "label": f"{key} {_speed(rate)}", "rate_deg_s": rate})
        default = "utility"
    else:
        for multiple in GENERIC_MULTIPLES:
            rate = multiple * SIDEREAL_RATE_DEG_S
            if rate < limit:
                label = f"{multiple:g}× sidereal ({_speed(rate)})"
                choices.append({"key": f"{multiple:g}", "label": label, "rate_deg_s": rate})
        choices.append({"key": "max", "label": f"max ({_speed(limit)})", "rate_deg_s": limit})
        default = "128" if any(c["key"] == "128" for c in choices) else "max"
    return {"hand_control": kind, "choices": choices, "default": default}


def _button(label: str, title: str, axis: str, sign: int) -> dict[str, object]:
    return {"label": label, "title": title, "axis": axis, "sign": sign}


def pad_json(mount: Mount, state: MountState) -> dict[str, object]:
    """What each of the pad's four positions (``up``, ``down``, ``left``, ``right``) is called
    and which axis and sign it turns now."""
    mode = mount.capabilities.alignment_mode
    if mode is AlignmentMode.ALT_AZ:
        return {
            "frame": "altaz",
            "up": _button("Up", "altitude up", "secondary", 1),
            "down": _button("Down", "altitude down", "secondary", -1),
            "left": _button("Left", "azimuth down (anticlockwise)", "primary", -1),
            "right": _button("Right", "azimuth up (clockwise)", "primary", 1),
        }
    north = mount.site.latitude_deg >= 0.0
    hemisphere = 1 if north else -1
    # Forwards on the polar axis turns westwards (hour angle up) in the north.
    east = -hemisphere
    normal = PierSide.EAST if north else PierSide.WEST
    side = state.pier_side
    if mode is AlignmentMode.GERMAN_POLAR and side is PierSide.UNKNOWN:
        up = _button("Dec +", "declination up (pier side unknown)", "secondary", 1)
        down = _button("Dec −", "declination down (pier side unknown)", "secondary", -1)
    else:
        flipped = mode is AlignmentMode.GERMAN_POLAR and side is not normal
        sign = hemisphere * (-1 if flipped else 1)
        up = _button("N", "north (declination up)", "secondary", sign)
        down = _button("S", "south (declination down)", "secondary", -sign)
    return {
        "frame": "equatorial",
        "up": up,
        "down": down,
        "left": _button("E", "east (right ascension up)", "primary", east),
        "right": _button("W", "west (right ascension down)", "primary", -east),
    }
