"""The PC-side pointing correction: syncs kept by scopelink, the model fitted to them, and the
readings and gotos it corrects (docs/pointing.md).

A sync the device refuses (a SynScan hand control beyond ~7° or before its alignment), cannot
make, or would make worse than scopelink (a hand control's sync is one local offset) is kept
here as a pair: where the mount *read* and where the tube truly pointed (the sync target). The
:mod:`~scopelink.mount.pointing_model` fitted to the pairs maps every reading to where the tube
really points (:meth:`PointingCorrection.correct`) and every goto target to the position the
device must be sent to (:meth:`PointingCorrection.reading_of`). ``Mount`` applies it below every
front end; the pairs are kept per device in :class:`~scopelink.mount.memory.DeviceMemory` and
forgotten when the mount reports a new alignment.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from scopelink.astro import (
    Site,
    angular_separation_deg,
    j2000_to_apparent,
    j2000_to_observed,
    observed_to_j2000,
)
from scopelink.mount.errors import InvalidValueError, LimitError
from scopelink.mount.limits import Limits
from scopelink.mount.memory import DeviceMemory, RecordError
from scopelink.mount.pointing_model import FittedModel, ModelFrame, fit
from scopelink.mount.types import Identity, MountState

__all__ = ["POINTING_RECORD", "REPLACE_WITHIN_DEG", "PointingCorrection", "SyncPoint", "device_key"]

POINTING_RECORD = "pointing"
"""The :class:`DeviceMemory` record name of the syncs."""
REPLACE_WITHIN_DEG = 2.0
"""A sync whose reading lies within this of an earlier one's replaces it (the observer centred
the same place again: the newer is the better)."""
_RECORD_VERSION = 1
_logger = logging.getLogger(__name__)


def device_key(identity: Identity) -> str:
    """The key a device's records are kept under: protocol, model and link."""
    return f"{identity.protocol}-{identity.model}-{identity.link}"


@dataclass(frozen=True, slots=True)
class SyncPoint:
    """One sync kept on the PC: the mount's reading and the true position (observed alt/az at
    ``at``), and the J2000 target the sync named."""

    at: datetime
    ra_j2000_hours: float
    dec_j2000_deg: float
    reading: tuple[float, float]
    true: tuple[float, float]

    def record(self) -> dict[str, Any]:
        return {
            "at": self.at.isoformat(),
            "ra_j2000_hours": self.ra_j2000_hours,
            "dec_j2000_deg": self.dec_j2000_deg,
            "reading_alt_az": list(self.reading),
            "true_alt_az": list(self.true),
        }

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> SyncPoint:
        reading, true = record["reading_alt_az"], record["true_alt_az"]
        point = cls(
            datetime.fromisoformat(record["at"]),
            float(record["ra_j2000_hours"]),
            float(record["dec_j2000_deg"]),
            (float(reading[0]), float(reading[1])),
            (float(true[0]), float(true[1])),
        )
        values = (point.ra_j2000_hours, point.dec_j2000_deg, *point.reading, *point.true)
        if not all(math.isfinite(v) for v in values) or not all(
            -90.0 <= alt <= 90.0 for alt in (point.reading[0], point.true[0])
        ):
            raise ValueError(f"a sync of {point.at.isoformat()} holds impossible angles")
        return point


_PLACE_FIELDS = (
    "ra_j2000_hours",
    "dec_j2000_deg",
    "ra_of_date_hours",
    "dec_of_date_deg",
    "alt_deg",
    "az_deg",
)
"""The fields of a state that say where the mount points (what the correction moves)."""


def _position(state: MountState) -> tuple[float | None, ...]:
    return (state.ra_j2000_hours, state.dec_j2000_deg, state.alt_deg, state.az_deg)


class PointingCorrection:
    """The syncs kept on the PC for one mount and the model fitted to them."""

    def __init__(self) -> None:
        self._syncs: list[SyncPoint] = []
        self._frame: ModelFrame | None = None
        self._model: FittedModel | None = None
        self._memory: DeviceMemory | None = None
        self._last_aligned: bool | None = None
        self._corrected_key: tuple[float | None, ...] | None = None
        self._latitude_deg: float | None = None
        """The site's latitude when the syncs were taken (alt/az pairs belong to one site)."""
        self.raw_state: MountState | None = None
        """The last reading as the device gave it (before correction)."""
        self.generation = 0
        """Counts the model's changes (a refit: syncs added, removed, dropped, the frame): a
        correction made under another generation is not the current one."""

    # --- the syncs and the model ----------------------------------------------------------------

    @property
    def syncs(self) -> tuple[SyncPoint, ...]:
        return tuple(self._syncs)

    @property
    def active(self) -> bool:
        """Whether any sync is kept on the PC (then every reading and goto is corrected)."""
        return bool(self._syncs)

    def set_frame(self, frame: ModelFrame) -> None:
        """The mount's kind and latitude (the model is refitted when they change). Syncs taken
        at another latitude are dropped from use (their record is left alone: a command run with
        another configured site must not wipe the model of the observatory's)."""
        if frame is self._frame or frame == self._frame:  # once per reading: identity first
            return
        self._frame = frame
        known = self._latitude_deg
        if self._syncs and known is not None and abs(known - frame.latitude_deg) > 0.01:
            self.drop(f"they were taken at latitude {known:+.4f}°, the site is now elsewhere")
        self._refit()

    def drop(self, why: str) -> None:
        """Stop using the syncs for this run (their record is kept), saying why in the log."""
        if self._syncs:
            _logger.warning("the %d syncs kept on the PC are not used: %s", len(self._syncs), why)
        self._syncs = []
        self._memory = None  # the record stays as it is
        self._refit()

    @property
    def model(self) -> FittedModel | None:
        return self._model

    def _refit(self) -> None:
        self._corrected_key = None  # the next reading is corrected afresh
        self.generation += 1
        if self._frame is None or not self._syncs:
            self._model = None
            return
        readings = [s.reading for s in self._syncs]
        self._model = fit(self._frame, readings, [s.true for s in self._syncs])

    def _with(self, point: SyncPoint) -> list[SyncPoint]:
        """The syncs with ``point`` added, replacing those it lies within ``REPLACE_WITHIN_DEG``
        of (the mount's reading: the same place of the mount's frame, centred again)."""
        kept = [
            s
            for s in self._syncs
            if angular_separation_deg(s.reading[1], s.reading[0], *point.reading[::-1])
            > REPLACE_WITHIN_DEG
        ]
        return [*kept, point]

    def trial(self, point: SyncPoint) -> FittedModel:
        """The model with ``point`` added (nothing kept)."""
        assert self._frame is not None
        syncs = self._with(point)
        return fit(self._frame, [s.reading for s in syncs], [s.true for s in syncs])

    def keep(
        self, ra_j2000_hours: float, dec_j2000_deg: float, site: Site, reach: float, limits: Limits
    ) -> None:
        """Keep a sync on the last raw reading (:attr:`raw_state`), unless the model with it
        would move the sky too far (:meth:`check_reach`: ``LimitError``, nothing kept)."""
        raw = self.raw_state
        if raw is None or raw.alt_deg is None or raw.az_deg is None:
            raise LimitError("the mount has not reported where it points: no sync was kept")
        true = j2000_to_observed(ra_j2000_hours, dec_j2000_deg, raw.read_at, site)
        point = SyncPoint(
            raw.read_at, ra_j2000_hours, dec_j2000_deg, (raw.alt_deg, raw.az_deg), true
        )
        self.check_reach(self.trial(point), reach, limits.max_sync_deg)
        self.add(point)

    def recheck(self, reach: float, limit_deg: float) -> None:
        """Stop using a (restored) model that moves the sky farther than ``limit_deg`` now."""
        if self._model is not None:
            try:
                self.check_reach(self._model, reach, limit_deg)
            except LimitError as error:
                self.drop(str(error))

    def add(self, point: SyncPoint) -> None:
        if self._frame is not None:
            self._latitude_deg = self._frame.latitude_deg
        self._syncs = self._with(point)
        self._refit()
        self._save()

    def remove(self, number: int) -> SyncPoint:
        """Forget sync ``number`` (1-based, as listed)."""
        if not 1 <= number <= len(self._syncs):
            raise InvalidValueError(
                f"there is no sync {number}: the pointing model has {len(self._syncs)}"
            )
        point = self._syncs.pop(number - 1)
        self._refit()
        self._save()
        return point

    def clear(self) -> None:
        self._syncs.clear()
        self._refit()
        self._save()

    def residuals_arcmin(self) -> list[float]:
        """Each sync's distance (arcmin) from where the model puts it."""
        model = self._model
        if model is None:
            return []
        return [model.residual_arcmin(s.reading, s.true) for s in self._syncs]

    def summary(self) -> dict[str, Any]:
        """What ``scopelink pointing`` and the dashboard show."""
        residuals = self.residuals_arcmin()
        model = self._model
        rms = math.sqrt(sum(r * r for r in residuals) / len(residuals)) if residuals else None
        return {
            "active": self.active,
            "terms_arcmin": model.terms_arcmin() if model else {},
            "fitted": list(model.fitted) if model else [],
            "rms_arcmin": rms,
            "syncs": [
                {"number": n, **s.record(), "residual_arcmin": r}
                for n, (s, r) in enumerate(zip(self._syncs, residuals, strict=True), start=1)
            ],
        }

    # --- corrections ----------------------------------------------------------------------------

    def reading_of(self, alt_deg: float, az_deg: float) -> tuple[float, float]:
        """Where the device must point (its frame) for the tube to point at this alt/az."""
        if self._model is None:
            return alt_deg, az_deg
        return self._model.reading_of(alt_deg, az_deg)

    def correct(self, state: MountState, site: Site) -> MountState:
        """``state`` with its position moved to where the tube really points (a state this
        object already corrected passes unchanged, so republishing never corrects twice)."""
        if self._corrected_key is not None and _position(state) == self._corrected_key:
            return state
        self.raw_state = state
        model = self._model
        if model is None or state.alt_deg is None or state.az_deg is None:
            self._corrected_key = _position(state)
            return state
        alt, az = model.true_of(state.alt_deg, state.az_deg)
        ra, dec = observed_to_j2000(alt, az, state.read_at, site)
        values = (ra, dec, *j2000_to_apparent(ra, dec, state.read_at), alt, az)
        place: dict[str, Any] = dict(zip(_PLACE_FIELDS, values, strict=True))
        corrected = dataclasses.replace(state, **place)
        self._corrected_key = _position(corrected)
        return corrected

    def observe(self, state: MountState, site: Site) -> MountState:
        """What every published state goes through, in one pass: :meth:`observe_alignment`, then
        :meth:`correct` (without a model the reading passes as it is, kept as :attr:`raw_state`:
        no key to compare, no state rebuilt)."""
        if state.connected and state.aligned is not self._last_aligned:
            self.observe_alignment(state)
        if self._model is None:
            self.raw_state = state
            return state
        return self.correct(state, site)

    def recorrected(self, current: MountState, site: Site) -> MountState | None:
        """``current`` (the published state) with the last raw reading's position corrected
        afresh, after the model changed; None while not connected or before any reading."""
        raw = self.raw_state
        if raw is None or not current.connected:
            return None
        fresh = self.correct(raw, site)  # what the next publish then recognises as corrected
        place: dict[str, Any] = {n: getattr(fresh, n) for n in ("read_at", *_PLACE_FIELDS)}
        return dataclasses.replace(current, **place)

    def check_reach(self, model: FittedModel, reach_deg: float, limit_deg: float) -> None:
        """Raise :class:`LimitError` if ``model`` moves any position above the horizon farther
        than ``limit_deg`` less the device's own sync ``reach_deg``: a PC-side model may not
        move the frame the limits are judged in further than a device sync could."""
        zero = FittedModel(model.frame, (0.0,) * 5, ())
        worst = 0.0
        for alt in (*range(0, 90, 5), 89.9):
            for az in range(0, 360, 15):
                true = (float(alt), float(az))
                worst = max(worst, zero.residual_arcmin(model.reading_of(*true), true))
        shift_deg = worst / 60.0
        if not shift_deg + reach_deg <= limit_deg:
            raise LimitError(
                f"with this sync the pointing model would shift positions by up to "
                f"{shift_deg + reach_deg:.2f}°, beyond limits.max_sync_deg ({limit_deg:g}°): "
                "nothing was kept (check the sync targets, or clear the model with "
                "'scopelink pointing clear')"
            )

    # --- alignment and persistence --------------------------------------------------------------

    def observe_alignment(self, state: MountState) -> None:
        """Forget the syncs when the mount reports a new alignment (unaligned, then aligned)."""
        if not state.connected:
            return
        if self._last_aligned is False and state.aligned and self._syncs:
            _logger.info("the mount reports a new alignment: the pointing model is forgotten")
            self.clear()
        self._last_aligned = state.aligned

    def attach(self, memory: DeviceMemory, *, aligned: bool | None) -> None:
        """Keep the syncs in ``memory`` from now on, starting from what it holds (unless it was
        recorded unaligned and the mount is aligned now: a new alignment since)."""
        self._memory = memory
        self._syncs = []
        self._refit()
        try:
            record = memory.load(POINTING_RECORD)
        except (RecordError, OSError) as error:  # left as it is; not written over
            _logger.warning("pointing model not restored, nor saved this run: %s", error)
            self._memory = None
            return
        if record is None or record.get("version") != _RECORD_VERSION:
            return
        if aligned and record.get("aligned") is False:
            self._save()  # forgets the record: a new alignment since it was made
            return
        try:
            self._syncs = [SyncPoint.from_record(r) for r in record.get("syncs", [])]
        except (KeyError, TypeError, ValueError, IndexError) as error:
            _logger.warning("pointing model in %s not restored: %s", memory.directory, error)
            self._syncs = []
        self._last_aligned = record.get("aligned")
        latitude = record.get("latitude_deg")
        self._latitude_deg = float(latitude) if isinstance(latitude, int | float) else None
        frame, self._frame = self._frame, None
        if frame is not None:
            self.set_frame(frame)  # checks the latitude, and fits

    def _save(self) -> None:
        if self._memory is None:
            return
        record = {
            "version": _RECORD_VERSION,
            "aligned": self._last_aligned,
            "latitude_deg": self._latitude_deg,
            "syncs": [s.record() for s in self._syncs],
        }
        try:
            if self._syncs:
                self._memory.save(POINTING_RECORD, record)
            else:
                self._memory.forget(POINTING_RECORD)
        except OSError as error:
            _logger.warning("pointing model not saved in %s: %s", self._memory.directory, error)
