"""What the Sky Tracker's arrows can do: the rates it supports and the buttons for a motion.

The box has no rate command. An arrow moves an axis at a speed set by the mode: 4°/s in
UTILITY (no tracking), ±8 arcmin/s on top of tracking in TRACK, ±``K`` arcsec/s (1-255, set per
axis) on top of tracking in GUIDE. A requested rate is mapped to the nearest of these.
"""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.mount import GuideDirection, MountAxis
from scopelink.protocol.skytracker import Direction, TrackerMode

__all__ = [
    "GUIDE_SPEED_MAX_ARCSEC_S",
    "MAX_SKYTRACKER_TRACKING_OFFSET_ARCSEC_S",
    "TRACK_ARROW_ARCSEC_S",
    "UTILITY_ARROW_ARCSEC_S",
    "AxisMotion",
    "ButtonPlan",
    "axis_motion",
    "guide_button",
    "plan_buttons",
]

UTILITY_ARROW_ARCSEC_S = 4.0 * 3600.0
"""UTILITY mode: an arrow slews at up to 4°/s (spec)."""
TRACK_ARROW_ARCSEC_S = 8.0 * 60.0
"""TRACK mode: an arrow adds or subtracts 8 arcmin/s to the track rate (spec)."""
GUIDE_SPEED_MAX_ARCSEC_S = 255
"""GUIDE mode: an arrow adds the ``K`` speed, 1-255 arcsec/s per axis (spec)."""

MAX_SKYTRACKER_TRACKING_OFFSET_ARCSEC_S = 120.0
"""The largest custom rate on each of RA and Dec: both at once are 170″/s on the sky, so up to
about 45° of altitude (where an azimuth rate on the sky needs 1/cos(alt) on the axis) the loop
still has room for its corrections within the box's 255″/s guide speed."""


@dataclass(frozen=True, slots=True)
class AxisMotion:
    """How to move one axis: press ``direction`` in ``mode``; in GUIDE with ``guide_speed``."""

    direction: Direction
    mode: TrackerMode
    guide_speed_arcsec_s: int | None
    rate_deg_s: float
    """The signed rate this gives on top of tracking (UTILITY: instead of tracking)."""


_POSITIVE = {MountAxis.PRIMARY: Direction.RIGHT, MountAxis.SECONDARY: Direction.UP}
_NEGATIVE = {MountAxis.PRIMARY: Direction.LEFT, MountAxis.SECONDARY: Direction.DOWN}


def axis_motion(axis: MountAxis, rate_deg_s: float) -> AxisMotion | None:
    """The arrow and mode nearest to ``rate_deg_s`` on ``axis``; None for 0 (stop).

    PRIMARY is azimuth (positive: compass azimuth increasing, the RIGHT arrow, clockwise seen
    from above); SECONDARY is altitude (positive: UP). Up to 255 arcsec/s the GUIDE speed is set
    to the rate rounded to whole arcsec/s (at least 1); above, the nearest of 255 arcsec/s
    (GUIDE), 8 arcmin/s (TRACK) and 4°/s (UTILITY) in absolute difference.
    """
    if rate_deg_s == 0.0:
        return None
    direction = _POSITIVE[axis] if rate_deg_s > 0 else _NEGATIVE[axis]
    sign = 1.0 if rate_deg_s > 0 else -1.0
    speed = abs(rate_deg_s) * 3600.0
    if speed <= GUIDE_SPEED_MAX_ARCSEC_S:
        guide = max(1, min(GUIDE_SPEED_MAX_ARCSEC_S, round(speed)))
        return AxisMotion(direction, TrackerMode.GUIDE, guide, sign * guide / 3600.0)
    choices = (
        (float(GUIDE_SPEED_MAX_ARCSEC_S), TrackerMode.GUIDE),
        (TRACK_ARROW_ARCSEC_S, TrackerMode.TRACK),
        (UTILITY_ARROW_ARCSEC_S, TrackerMode.UTILITY),
    )
    nearest, mode = min(choices, key=lambda choice: abs(choice[0] - speed))
    guide_speed = GUIDE_SPEED_MAX_ARCSEC_S if mode is TrackerMode.GUIDE else None
    return AxisMotion(direction, mode, guide_speed, sign * nearest / 3600.0)


_GUIDE_BUTTONS: dict[GuideDirection, tuple[MountAxis, Direction]] = {
    GuideDirection.NORTH: (MountAxis.SECONDARY, Direction.UP),
    GuideDirection.SOUTH: (MountAxis.SECONDARY, Direction.DOWN),
    # Facing south, east is to the left: compass azimuth decreasing.
    GuideDirection.EAST: (MountAxis.PRIMARY, Direction.LEFT),
    GuideDirection.WEST: (MountAxis.PRIMARY, Direction.RIGHT),
}


def guide_button(direction: GuideDirection) -> tuple[MountAxis, Direction]:
    """The axis and arrow of a guide pulse: north/south up/down, east/west left/right."""
    return _GUIDE_BUTTONS[direction]


@dataclass(frozen=True, slots=True)
class ButtonPlan:
    """What the box must be told so that exactly the wanted arrows move at the wanted speeds."""

    mode: TrackerMode
    guide_speeds_arcsec_s: tuple[int, int]
    """``K`` speeds (azimuth, elevation)."""
    pressed: tuple[Direction, ...]
    rest_mode: TrackerMode | None
    """The mode to come back to once nothing is pressed (None: nothing pressed now)."""

    @property
    def all_pressed(self) -> Direction:
        combined = Direction(0)
        for direction in self.pressed:
            combined |= direction
        return combined


def plan_buttons(
    held: dict[MountAxis, AxisMotion],
    pulses: dict[MountAxis, Direction],
    *,
    pulse_speeds_arcsec_s: tuple[int, int],
    mode: TrackerMode | None,
    rest_mode: TrackerMode | None,
) -> ButtonPlan:
    """The mode, ``K`` speeds and arrows for the axes held by ``move_axis`` and the guide pulses
    under way; ``mode`` is the box's now, ``rest_mode`` the one from before the first arrow.

    Held motions set the mode (both share one); pulses alone need GUIDE; with nothing pressed
    the mode from before comes back. ``K`` is the pulse speed on an axis unless a GUIDE-mode
    motion holds that axis at its own speed.
    """
    pressed = tuple(motion.direction for motion in held.values()) + tuple(pulses.values())
    if pressed and rest_mode is None:
        rest_mode = mode
    if held:
        wanted = next(iter(held.values())).mode
    elif pulses:
        wanted = TrackerMode.GUIDE
    else:
        wanted = rest_mode or mode or TrackerMode.UTILITY
        rest_mode = None
    speeds = list(pulse_speeds_arcsec_s)
    for index, axis in enumerate((MountAxis.PRIMARY, MountAxis.SECONDARY)):
        motion = held.get(axis)
        if motion is not None and motion.guide_speed_arcsec_s is not None:
            speeds[index] = motion.guide_speed_arcsec_s
    return ButtonPlan(wanted, (speeds[0], speeds[1]), pressed, rest_mode)
