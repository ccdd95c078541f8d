"""Sky Tracker driver: the Mount API over the PC <-> Sky Tracker (+ Sky Commander) line.

See ``docs/drivers-skytracker.md``.
"""

from .calibration import CalibrationFactors, CalibrationRuleError
from .line import (
    BadReplyError,
    BusRefusedError,
    LineOptions,
    LineOutOfSyncError,
    ReplyTimeoutError,
    SkyTrackerLine,
)
from .motion import AxisMotion, ButtonPlan, axis_motion, guide_button, plan_buttons
from .mount import LinkFactory, SkyTrackerMount, SlewInProgressError

__all__ = [
    "AxisMotion",
    "BadReplyError",
    "BusRefusedError",
    "ButtonPlan",
    "CalibrationFactors",
    "CalibrationRuleError",
    "LineOptions",
    "LineOutOfSyncError",
    "LinkFactory",
    "ReplyTimeoutError",
    "SkyTrackerLine",
    "SkyTrackerMount",
    "SlewInProgressError",
    "axis_motion",
    "guide_button",
    "plan_buttons",
]
