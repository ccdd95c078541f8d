"""Sky Tracker driver: the Mount API over the PC <-> Sky Tracker (+ Sky Commander) line.

See ``docs/drivers-skytracker.md``.
"""

from .calibration import CalibrationFactors, CalibrationRuleError
from .line import (
    BadReplyError,
    BusRefusedError,
    LineOptions,
    ReplyTimeoutError,
    SkyTrackerLine,
)
from .motion import AxisMotion, axis_motion, guide_button
from .mount import LinkFactory, SkyTrackerMount, SlewInProgressError

__all__ = [
    "AxisMotion",
    "BadReplyError",
    "BusRefusedError",
    "CalibrationFactors",
    "CalibrationRuleError",
    "LineOptions",
    "LinkFactory",
    "ReplyTimeoutError",
    "SkyTrackerLine",
    "SkyTrackerMount",
    "SlewInProgressError",
    "axis_motion",
    "guide_button",
]
