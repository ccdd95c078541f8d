"""Non-volatile memory of the emulated devices: files that survive a restart and a ``kill -9``
(written with :func:`scopelink.links.storage.write_atomically`)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from scopelink.links.storage import remove_stale_temporaries, write_atomically
from scopelink.protocol.skytracker.commander_messages import STORED_SLOTS

OBJECTS_FILE = "skycommander-objects.json"
CALIBRATION_FILE = "skytracker-calibration.json"


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_bytes())
    except FileNotFoundError:
        return None


@dataclass(frozen=True, slots=True)
class StoredObject:
    """Coordinates in one slot of the Sky Commander's memory (J2000)."""

    ra_hours: float
    dec_degrees: float


class ObjectStore:
    """The Sky Commander's object slots ``L00``-``L58``, kept in ``directory``.

    Every :meth:`store` rewrites the whole file atomically (59 slots are a few kilobytes).
    A file that does not parse is an error: we never silently forget a user's objects.
    """

    def __init__(self, directory: Path) -> None:
        self.path = Path(directory) / OBJECTS_FILE
        remove_stale_temporaries(self.path)  # what a kill -9 mid-write left
        self._slots: dict[int, StoredObject] = {}
        raw = _read_json(self.path)
        if raw is not None:
            for slot_text, (ra_hours, dec_degrees) in raw["slots"].items():
                self._slots[int(slot_text)] = StoredObject(float(ra_hours), float(dec_degrees))

    def store(self, slot: int, item: StoredObject) -> None:
        """Put ``item`` in ``slot`` (0-58) and persist it before returning."""
        if slot not in STORED_SLOTS:
            raise ValueError(f"stored object slots are 00-58, got {slot}")
        slots = {**self._slots, slot: item}
        document = {
            "slots": {
                f"{number:02d}": [entry.ra_hours, entry.dec_degrees]
                for number, entry in sorted(slots.items())
            }
        }
        write_atomically(self.path, json.dumps(document, indent=1).encode())
        self._slots = slots

    def get(self, slot: int) -> StoredObject | None:
        """The object in ``slot``, or None when it was never stored."""
        return self._slots.get(slot)

    def items(self) -> dict[int, StoredObject]:
        """Every stored object by slot."""
        return dict(self._slots)


@dataclass(frozen=True, slots=True)
class Calibration:
    """The Sky Tracker's motor calibration factors (``S``/``s``), as sent on the wire."""

    azimuth_factor: float
    elevation_factor: float


class CalibrationStore:
    """The Sky Tracker's calibration EEPROM, kept in ``directory``; ``default`` until written."""

    def __init__(self, directory: Path, default: Calibration) -> None:
        self.path = Path(directory) / CALIBRATION_FILE
        raw = _read_json(self.path)
        self.calibration = (
            default
            if raw is None
            else Calibration(float(raw["azimuth_factor"]), float(raw["elevation_factor"]))
        )

    def write(self, calibration: Calibration) -> None:
        """Persist ``calibration`` before returning."""
        document = {
            "azimuth_factor": calibration.azimuth_factor,
            "elevation_factor": calibration.elevation_factor,
        }
        write_atomically(self.path, json.dumps(document).encode())
        self.calibration = calibration
