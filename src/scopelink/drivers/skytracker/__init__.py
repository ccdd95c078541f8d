"""Sky Tracker driver: the Mount API over the PC <-> Sky Tracker (+ Sky Commander) line.

One class per concern, each building on the one before:

- `base`: `SkyTrackerBase`, construction, identity, the line and the state it last reported;
- `connection`: `SkyTrackerConnection`, open and identify, reconnect, calibration;
- `polling`: `SkyTrackerPolling`, read the state (``R``, the position through the bus);
- `guiding`: `SkyTrackerGuiding`, the guide speeds (``K``) and guide rates;
- `rates`: `SkyTrackerRates`, custom tracking rates by timed presses in a closed loop;
- `mount`: `SkyTrackerMount`, the commands (connect, goto, sync, abort, tracking, arrows, pulses).

Beside them: `exchange` (`SkyTrackerLine`, one exchange at a time, the Sky Commander bus,
resynchronisation), `motion` (which arrows and modes give a rate), `presses` (timed presses:
a mean rate finer than ``K``'s steps), `calibration`.
The Sky Commander alone on its port: `commander_mount` (`SkyCommanderMount`); its object memory
and a mirror of it: `memory`, `plan` (a night's list); push-to figures: `pushto`; the sync both
drivers do (``L99``, ``N``, read back): `realign`.

See ``docs/drivers-skytracker.md``.
"""

from .calibration import CalibrationFactors, CalibrationRuleError
from .commander_mount import SkyCommanderMount
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
    "SkyCommanderMount",
    "SkyTrackerLine",
    "SkyTrackerMount",
    "SlewInProgressError",
    "axis_motion",
    "guide_button",
    "plan_buttons",
]
