"""Park, power off, resume: what scopelink records when the mount arrives parked, and what
``unpark`` puts back (``docs/parking.md``).

When the mount is first seen parked (arrived and stopped), :class:`ParkKeeper` writes one record
(``park.json``) to the device's :class:`~scopelink.mount.memory.DeviceMemory`: where it points
(observed alt/az, pier side), its axis positions when the driver knows them, whether it was
aligned, the net sync frame, and the PC-side pointing correction if the mount keeps one. ``unpark``
reads it back and lets a driver that can (:class:`AxisResuming`, the SynScan driver) put the axis
positions back into a hand control that forgot them in a power cycle. The record is consumed by
that unpark whatever the outcome (a later power cycle without a new park finds none), except when
the unpark is refused before anything was judged (the mount moving, an unreadable record).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from scopelink.astro import angular_separation_deg
from scopelink.mount.errors import MountError
from scopelink.mount.limits import Limits
from scopelink.mount.memory import DeviceMemory, RecordError, default_state_dir
from scopelink.mount.syncs import SyncFrame
from scopelink.mount.types import Identity, MountState, PierSide

__all__ = [
    "PARK_RECORD",
    "AxisResuming",
    "ParkKeeper",
    "ParkRecord",
    "ParkRecordError",
    "Parkable",
    "PointingCorrectionKeeper",
    "Resume",
]

logger = logging.getLogger(__name__)

PARK_RECORD = "park"
"""The record's name in the device's memory (``park.json``)."""

RECORD_VERSION = 1


class ParkRecordError(MountError):
    """Unpark cannot use the park record now (the message says why and what to do)."""


@dataclass(frozen=True, slots=True)
class ParkRecord:
    """What the mount was when it arrived parked."""

    alt_deg: float
    az_deg: float
    pier_side: PierSide
    aligned: bool
    parked_at: datetime
    axes_deg: tuple[float, float] | None = None
    """The axis positions (degrees, the driver's convention: ``docs/parking.md``), if known."""
    sync_frame_deg: tuple[float, float] = (0.0, 0.0)
    """The net correction syncs had made (``Mount.sync_frame``), axis degrees."""
    correction: dict[str, Any] | None = None
    """The PC-side pointing correction (:class:`PointingCorrectionKeeper`), if any."""

    def to_json(self) -> dict[str, Any]:
        return {
            "version": RECORD_VERSION,
            "alt_deg": self.alt_deg,
            "az_deg": self.az_deg,
            "pier_side": self.pier_side.value,
            "aligned": self.aligned,
            "parked_at": self.parked_at.isoformat(),
            "axes_deg": list(self.axes_deg) if self.axes_deg is not None else None,
            "sync_frame_deg": list(self.sync_frame_deg),
            "correction": self.correction,
        }

    @classmethod
    def from_json(cls, data: dict[str, Any], where: Path) -> ParkRecord:
        """The record in ``data``; :class:`ParkRecordError` naming ``where`` if it is not one."""
        try:
            if data.get("version") != RECORD_VERSION:
                raise ValueError(f"version {data.get('version')!r}, expected {RECORD_VERSION}")
            axes = data["axes_deg"]
            record = cls(
                alt_deg=float(data["alt_deg"]),
                az_deg=float(data["az_deg"]),
                pier_side=PierSide(data["pier_side"]),
                aligned=bool(data["aligned"]),
                parked_at=datetime.fromisoformat(data["parked_at"]),
                axes_deg=None if axes is None else (float(axes[0]), float(axes[1])),
                sync_frame_deg=(float(data["sync_frame_deg"][0]), float(data["sync_frame_deg"][1])),
                correction=data.get("correction"),
            )
        except (KeyError, IndexError, TypeError, ValueError) as error:
            message = f"{where} is not a park record ({error}); fix or delete it"
            raise ParkRecordError(message) from None
        numbers = (record.alt_deg, record.az_deg, *(record.axes_deg or ()), *record.sync_frame_deg)
        if not all(math.isfinite(n) for n in numbers):
            raise ParkRecordError(f"{where} holds a value that is not finite; fix or delete it")
        return record


@dataclass(frozen=True, slots=True)
class Resume:
    """What an unpark did with the park record: ``message`` in one line, ``restored`` when the
    axis positions (and the sync frame and correction) were put back."""

    message: str
    restored: bool = False
    record: ParkRecord | None = None


@runtime_checkable
class AxisResuming(Protocol):
    """A driver that can put its axis positions back after a power cycle (SynScan)."""

    def park_axes(self, state: MountState) -> tuple[float, float] | None:
        """The axis positions of the parked mount in ``state`` (None when not known exactly)."""

    async def resume_axes(self, record: ParkRecord, state: MountState) -> Resume:
        """Judge the record against the device and restore what it says, or say why not."""


@runtime_checkable
class PointingCorrectionKeeper(Protocol):
    """The hook for a PC-side pointing correction (issue #15 part 1): a mount that keeps one
    gives it as a JSON-able dict at park and takes it back at a resume."""

    def pointing_correction_record(self) -> dict[str, Any] | None: ...

    def restore_pointing_correction(self, record: dict[str, Any]) -> None: ...


class Parkable(Protocol):
    """What the keeper needs of a mount (a ``Mount``; named here so that ``base`` may import
    this module without a cycle)."""

    @property
    def identity(self) -> Identity: ...

    @property
    def sync_frame(self) -> SyncFrame: ...

    async def refresh(self) -> MountState: ...


class ParkKeeper:
    """Writes the park record when the mount arrives parked; reads it back at unpark.

    Off until :meth:`enable` (the command line and ``scopelink serve`` enable it with the
    per-user state directory; a library user chooses).
    """

    def __init__(self) -> None:
        self.state_dir: Path | None = None
        self.last_resume = ""
        """What the last unpark did with the record (one line, for the front ends)."""
        self._was_parked = False
        self._resuming = False
        """An unpark is judging the record: the readings it takes (parked, once the counters
        are back) are no new park."""

    def enable(self, state_dir: Path | None = None) -> None:
        self.state_dir = state_dir or default_state_dir()

    def memory_for(self, mount: Parkable) -> DeviceMemory | None:
        """The device's memory (by protocol, model and link), or None while disabled."""
        if self.state_dir is None:
            return None
        identity = mount.identity
        key = f"{identity.protocol}-{identity.model}-{identity.link}"
        return DeviceMemory(key, self.state_dir)

    def observe(self, mount: Parkable, state: MountState) -> None:
        """Record the park when ``state`` is the first parked one (never raises: a record
        that cannot be written is logged, and the mount is parked all the same)."""
        arrived = state.parked and not self._was_parked
        self._was_parked = state.parked
        if not arrived or self._resuming:
            return
        memory = self.memory_for(mount)
        if memory is None or state.alt_deg is None or state.az_deg is None:
            return
        axes = mount.park_axes(state) if isinstance(mount, AxisResuming) else None
        correction = None
        if isinstance(mount, PointingCorrectionKeeper):
            correction = mount.pointing_correction_record()
        frame = mount.sync_frame
        record = ParkRecord(
            alt_deg=state.alt_deg,
            az_deg=state.az_deg,
            pier_side=state.pier_side,
            aligned=state.aligned,
            parked_at=state.read_at,
            axes_deg=axes,
            sync_frame_deg=(frame.primary_deg, frame.secondary_deg),
            correction=correction,
        )
        try:
            memory.save(PARK_RECORD, record.to_json())
        except OSError as error:
            logger.warning("the park record could not be written: %s", error)

    def load(self, mount: Parkable) -> ParkRecord | None:
        memory = self.memory_for(mount)
        if memory is None:
            return None
        try:
            data = memory.load(PARK_RECORD)
        except RecordError as error:
            raise ParkRecordError(str(error)) from None
        except OSError as error:
            where = memory.path(PARK_RECORD)
            raise ParkRecordError(f"{where} cannot be read ({error.strerror or error})") from None
        return None if data is None else ParkRecord.from_json(data, memory.path(PARK_RECORD))

    async def resume(self, mount: Parkable) -> Resume:
        """Judge and use the park record for an unpark (see the module's docstring).

        The record is removed before anything is restored (a record that cannot be removed is
        never used: a later unpark would restore it again), and written back only when the
        driver finds the mount moving (nothing was judged)."""
        record = self.load(mount)
        memory = self.memory_for(mount)
        if record is None or memory is None:
            resume = Resume("no park record: nothing to restore")
        else:
            state = await mount.refresh()  # read now: a power cycle may be seconds old
            if state.slewing:
                raise ParkRecordError(
                    "the mount is moving: nothing was restored (axis positions are never set "
                    "while it moves); stop it and unpark again"
                )
            try:
                memory.forget(PARK_RECORD)  # used once: a later power cycle needs a new park
            except OSError as error:
                raise ParkRecordError(
                    f"{memory.path(PARK_RECORD)} cannot be removed ({error.strerror or error}): "
                    "nothing was restored"
                ) from None
            self._resuming = True
            try:
                resume = await self._judge(mount, record, state, memory)
            finally:
                self._resuming = False
        self.last_resume = resume.message
        logger.info("unpark: %s", resume.message)
        return resume

    async def _judge(
        self, mount: Parkable, record: ParkRecord, state: MountState, memory: DeviceMemory
    ) -> Resume:
        if not isinstance(mount, AxisResuming):
            kept = "this mount keeps its own position: nothing to restore"
            resume = Resume(kept, restored=True, record=record)
        else:
            try:
                resume = await mount.resume_axes(record, state)
            except ParkRecordError:  # refused before judging (moving): keep it for the retry
                memory.save(PARK_RECORD, record.to_json())
                raise
        keeper = mount if isinstance(mount, PointingCorrectionKeeper) else None
        if resume.restored and record.correction is not None and keeper is not None:
            keeper.restore_pointing_correction(record.correction)
        return resume


def check_restore_agrees(record: ParkRecord, state: MountState, limits: Limits) -> float:
    """How far (degrees) the record is from where the device says it points; raises
    :class:`ParkRecordError` when farther than ``limits.max_sync_deg`` (the record is stale)."""
    if state.alt_deg is None or state.az_deg is None:
        raise ParkRecordError("the mount has not reported its position: nothing was restored")
    off = float(angular_separation_deg(state.az_deg, state.alt_deg, record.az_deg, record.alt_deg))
    if off > limits.max_sync_deg:
        raise ParkRecordError(
            f"the park record is stale: the still aligned hand control points {off:.2f}° from it "
            f"(more than limits.max_sync_deg {limits.max_sync_deg:g}°): nothing was restored"
        )
    return off
