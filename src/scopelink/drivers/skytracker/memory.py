"""The Sky Commander's object memory (``L00``-``L58``) as seen from the PC: what to write, and a
mirror of what scopelink last wrote (the box cannot be read back).

The mirror is one record of :class:`scopelink.mount.memory.DeviceMemory` per device
(``skycommander-slots.json`` under the device's directory), written after every acknowledged
slot, so an upload cut short by a lost link still shows the slots that landed. Decisions (limits,
clearing, the Sun) are in ``docs/drivers-skytracker.md``, "Sky Commander memory and push-to".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from scopelink.astro import Site, angular_separation_deg
from scopelink.astro.catalog import lookup
from scopelink.links import LinkError
from scopelink.mount import DeviceError, InvalidValueError, MountError, SunAvoidanceError
from scopelink.mount.memory import DeviceMemory, RecordError
from scopelink.protocol.skytracker.commander_messages import STORED_SLOTS, LoadObject

__all__ = [
    "MIRROR_RECORD",
    "SLOT_COUNT",
    "SUN_DRIFT_MARGIN_DEG",
    "ObjectStorer",
    "SlotEntry",
    "SlotMirror",
    "UploadInterruptedError",
    "check_away_from_sun",
    "mirror_key",
    "placeholder",
    "stored_object",
    "upload",
]

SLOT_COUNT = len(STORED_SLOTS)
"""59 slots, ``L00``-``L58``."""
MIRROR_RECORD = "skycommander-slots"
SUN_DRIFT_MARGIN_DEG = 1.0
"""Added to ``limits.sun_avoidance_deg`` when storing: a slot is kept for days, and the Sun moves
about 1° a day along the ecliptic."""


@runtime_checkable
class ObjectStorer(Protocol):
    """A driver that can write the Sky Commander's memory (both Sky Commander drivers)."""

    async def store_object(self, slot: int, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """Store J2000 coordinates in ``slot`` (0-58)."""


def stored_object(slot: int, ra_j2000_hours: float, dec_j2000_deg: float) -> LoadObject:
    """The ``Lnn`` command for a memory slot; :class:`InvalidValueError` for any other slot."""
    if slot not in STORED_SLOTS:
        raise InvalidValueError(f"Sky Commander memory slots are 00-58, not {slot}")
    return LoadObject(slot, ra_j2000_hours, dec_j2000_deg)


def mirror_key(link_spec: str) -> str:
    """The :class:`DeviceMemory` key of the Sky Commander reached on ``link_spec``."""
    return f"skycommander-{link_spec}"


def placeholder(site: Site) -> tuple[float, float]:
    """What ``clear`` writes: the elevated celestial pole (RA 0 h, Dec ±90°), always far from
    the Sun (at least 66°) and never below the horizon, easy to recognise on the box."""
    return 0.0, 90.0 if site.latitude_deg >= 0.0 else -90.0


def check_away_from_sun(
    label: str, ra_j2000_hours: float, dec_j2000_deg: float, when: datetime, radius_deg: float
) -> None:
    """Refuse to store a position within ``radius_deg`` (+ the drift margin) of the Sun: the box's
    own GOTO to a stored slot never passes through scopelink's checks. 0 turns it off."""
    if radius_deg <= 0.0:
        return
    sun = lookup("Sun", when)
    separation = angular_separation_deg(
        ra_j2000_hours * 15.0, dec_j2000_deg, sun.ra_hours * 15.0, sun.dec_deg
    )
    if separation < radius_deg + SUN_DRIFT_MARGIN_DEG:
        raise SunAvoidanceError(
            f"{label} is {separation:.1f}° from the Sun: not stored (the Sky Commander's own "
            f"GOTO would take the scope into the {radius_deg:g}° zone around it)"
        )


class UploadInterruptedError(DeviceError):
    """An upload stopped part-way; :attr:`written` holds the slots that landed (and are in the
    mirror)."""

    def __init__(self, message: str, written: Sequence[SlotEntry]) -> None:
        super().__init__(message)
        self.written = tuple(written)


@dataclass(frozen=True, slots=True)
class SlotEntry:
    """One slot as scopelink wrote it: J2000 coordinates and the name the user gave."""

    slot: int
    label: str
    ra_j2000_hours: float
    dec_j2000_deg: float
    written_at: str = ""
    """ISO 8601 UTC time of the acknowledgement (empty until written)."""

    def as_json(self) -> dict[str, Any]:
        return {
            "slot": self.slot,
            "label": self.label,
            "ra_j2000_hours": self.ra_j2000_hours,
            "dec_j2000_deg": self.dec_j2000_deg,
            "written_at": self.written_at,
        }


class SlotMirror:
    """What scopelink last wrote to one Sky Commander's memory, by slot."""

    def __init__(self, device_key: str, state_dir: Path | None = None) -> None:
        self.memory = DeviceMemory(device_key, state_dir)

    @property
    def path(self) -> Path:
        return self.memory.path(MIRROR_RECORD)

    def entries(self) -> dict[int, SlotEntry]:
        """Every slot scopelink wrote and has not cleared; :class:`RecordError` for a bad file."""
        record = self.memory.load(MIRROR_RECORD)
        if record is None:
            return {}
        try:
            entries = {}
            for item in record["slots"]:
                entry = SlotEntry(
                    int(item["slot"]),
                    str(item["label"]),
                    float(item["ra_j2000_hours"]),
                    float(item["dec_j2000_deg"]),
                    str(item.get("written_at", "")),
                )
                entries[entry.slot] = entry
        except (KeyError, TypeError, ValueError) as error:
            raise RecordError(
                f"{self.path} does not hold slots ({error!r}); fix or delete it"
            ) from None
        return entries

    def _save(self, entries: dict[int, SlotEntry]) -> None:
        slots = [entries[slot].as_json() for slot in sorted(entries)]
        self.memory.save(MIRROR_RECORD, {"slots": slots})

    def record(self, entry: SlotEntry) -> None:
        self._save({**self.entries(), entry.slot: entry})

    def forget(self, slots: Sequence[int] | None = None) -> None:
        """Forget ``slots`` (all when None); the box keeps whatever it holds."""
        if slots is None:
            self.memory.forget(MIRROR_RECORD)
            return
        entries = self.entries()
        for slot in slots:
            entries.pop(slot, None)
        self._save(entries)


async def upload(
    storer: ObjectStorer,
    mirror: SlotMirror,
    entries: Sequence[SlotEntry],
    now: datetime,
) -> list[SlotEntry]:
    """Write ``entries`` in order, recording each in ``mirror`` once the box acknowledged it.

    The entries are checked whole first (slots 00-58, no slot twice), so a bad one sends
    nothing; a failure on the line leaves the slots written before it recorded.
    """
    seen: set[int] = set()
    for entry in entries:
        stored_object(entry.slot, entry.ra_j2000_hours, entry.dec_j2000_deg)
        if entry.slot in seen:
            raise InvalidValueError(f"slot {entry.slot:02d} is given twice")
        seen.add(entry.slot)
    written: list[SlotEntry] = []
    for entry in entries:
        try:
            await storer.store_object(entry.slot, entry.ra_j2000_hours, entry.dec_j2000_deg)
        except (MountError, LinkError) as error:
            raise UploadInterruptedError(
                f"{error} ({len(written)} of {len(entries)} slots were written before it)",
                written,
            ) from error
        done = SlotEntry(  # as the box holds it: the wire carries 3 decimals
            entry.slot,
            entry.label,
            round(entry.ra_j2000_hours, 3) % 24.0,
            round(entry.dec_j2000_deg, 3),
            now.isoformat(timespec="seconds"),
        )
        mirror.record(done)
        written.append(done)
    return written
