"""Sky Tracker driver: the Mount API over the PC <-> Sky Tracker (+ Sky Commander) line.

See ``docs/drivers-skytracker.md``.
"""

from .calibration import CalibrationFactors, CalibrationRuleError
from .exchange import (
    DEFAULT_TIMEOUT_S,
    BadReplyError,
    BusOptions,
    BusRefusedError,
    LineOutOfSyncError,
    ReplyTimeoutError,
    SkyTrackerLine,
)
from .motion import AxisMotion, ButtonPlan, axis_motion, guide_button, plan_buttons
from .mount import SkyTrackerMount, SlewInProgressError

__all__ = [
    "DEFAULT_TIMEOUT_S",
    "AxisMotion",
    "BadReplyError",
    "BusOptions",
    "BusRefusedError",
    "ButtonPlan",
    "CalibrationFactors",
    "CalibrationRuleError",
    "LineOutOfSyncError",
    "ReplyTimeoutError",
    "SkyTrackerLine",
    "SkyTrackerMount",
    "SlewInProgressError",
    "axis_motion",
    "guide_button",
    "plan_buttons",
]
