"""Sky Tracker motor box and Sky Commander digital setting circles, emulated byte for byte.

See ``docs/emulators-skytracker.md``.
"""

from .commander import Alignment, SkyCommander
from .emulator import SkyCommanderEmulator, SkyTrackerEmulator, commander_for
from .line import StrictReceiver, resample
from .objects import Calibration, CalibrationStore, ObjectStore, StoredObject
from .port import DevicePort
from .tracker import HandBox, SkyTracker

__all__ = [
    "Alignment",
    "Calibration",
    "CalibrationStore",
    "DevicePort",
    "HandBox",
    "ObjectStore",
    "SkyCommander",
    "SkyCommanderEmulator",
    "SkyTracker",
    "SkyTrackerEmulator",
    "StoredObject",
    "StrictReceiver",
    "commander_for",
    "resample",
]
