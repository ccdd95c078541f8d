"""Sky Tracker driver: the Mount API over the PC <-> Sky Tracker (+ Sky Commander) line.

One class per concern, each building on the one before:

- `base`: `SkyTrackerBase`, construction, identity, the line and the state it last reported;
- `connection`: `SkyTrackerConnection`, open and identify, reconnect, calibration;
- `polling`: `SkyTrackerPolling`, read the state (``R``, the position through the bus);
- `mount`: `SkyTrackerMount`, the commands (connect, goto, sync, abort, tracking, arrows, pulses).

Beside them: `exchange` (`SkyTrackerLine`, one exchange at a time, the Sky Commander bus,
resynchronisation), `motion` (which arrows and modes give a rate), `calibration`.

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
