"""Errors the Mount API raises. Each says what happened and what to do."""


class MountError(Exception):
    """Base of every error a mount operation raises."""


class NotSupportedError(MountError):
    """This mount or firmware cannot do that (front ends answer 'not implemented')."""


class NotConnectedError(MountError):
    """The mount is not connected."""


class LimitError(MountError):
    """The request would move the mount below the horizon or past a limit; nothing was sent."""


class SunAvoidanceError(LimitError):
    """The request would point the mount into (or sweep it through) the zone around the Sun
    (``limits.sun_avoidance_deg``); nothing was sent."""


class ParkedError(MountError):
    """The mount is parked; unpark it first."""


class InvalidValueError(MountError, ValueError):
    """A coordinate, rate or duration outside its valid range."""


class DeviceError(MountError):
    """The device did not answer, or answered something that makes no sense."""


class StaleReadingError(DeviceError):
    """The last reading is older than the mount's ``stale_after_s``: it is not served as current
    (the message names its age and why no newer one came)."""


class SyncRefusedError(DeviceError):
    """The device did not take a sync (e.g. a hand control beyond its ~7°): ``Mount`` then keeps
    the sync on the PC (docs/pointing.md)."""
