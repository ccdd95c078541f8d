"""The protocol-neutral Mount API that every front end uses."""

from scopelink.mount.base import MAX_PULSE_GUIDE_MS, Mount, utc_now
from scopelink.mount.errors import (
    DeviceError,
    InvalidValueError,
    LimitError,
    MountError,
    NotConnectedError,
    NotSupportedError,
    ParkedError,
    StaleReadingError,
    SunAvoidanceError,
)
from scopelink.mount.limits import Limits
from scopelink.mount.polling import DEFAULT_STALE_AFTER_S, PollPolicy
from scopelink.mount.scheduling import Priority, WireScheduler
from scopelink.mount.types import (
    AlignmentMode,
    Capabilities,
    GuideDirection,
    Identity,
    MountAxis,
    MountState,
    ParkPosition,
    PierSide,
    SlewProgress,
    SlewTarget,
    TrackingMode,
)

__all__ = [
    "DEFAULT_STALE_AFTER_S",
    "MAX_PULSE_GUIDE_MS",
    "AlignmentMode",
    "Capabilities",
    "DeviceError",
    "GuideDirection",
    "Identity",
    "InvalidValueError",
    "LimitError",
    "Limits",
    "Mount",
    "MountAxis",
    "MountError",
    "MountState",
    "NotConnectedError",
    "NotSupportedError",
    "ParkPosition",
    "ParkedError",
    "PierSide",
    "PollPolicy",
    "Priority",
    "SlewProgress",
    "SlewTarget",
    "StaleReadingError",
    "SunAvoidanceError",
    "TrackingMode",
    "WireScheduler",
    "utc_now",
]
