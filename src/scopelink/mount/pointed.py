"""The Mount's frame: its site and limits, and the readings corrected by the syncs kept on the PC
(:mod:`scopelink.mount.pointing`) — every published state and every driver's ``refresh`` go
through :meth:`PointedMount._corrected`, so no front end ever sees an uncorrected position. Also
the net frame change that syncs sent to the device have made (:mod:`scopelink.mount.syncs`).

The layer between the state cache and the checked commands of :class:`~scopelink.mount.Mount`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from datetime import datetime

from scopelink.astro import Site, j2000_to_observed
from scopelink.mount.cache import StateCache
from scopelink.mount.limits import Limits
from scopelink.mount.memory import DeviceMemory
from scopelink.mount.pointing import PointingCorrection
from scopelink.mount.pointing_model import ModelFrame
from scopelink.mount.syncs import SyncFrame
from scopelink.mount.types import AlignmentMode, MountState

__all__ = ["PointedMount"]


class PointedMount(StateCache):
    """A state cache whose readings are corrected by the PC-side pointing model."""

    syncs_on_device: bool = True
    """Whether a sync goes to the device first (kept on the PC only if the device refuses it or
    has none); False keeps every sync in :attr:`pointing` (docs/pointing.md)."""

    def __init_subclass__(cls, **keywords: object) -> None:
        """Every ``refresh`` a driver defines returns the corrected reading (:attr:`pointing`)."""
        super().__init_subclass__(**keywords)
        original = cls.__dict__.get("refresh")
        if original is not None:

            @functools.wraps(original)
            async def refresh(self: PointedMount) -> MountState:
                return self._corrected(await original(self))

            setattr(cls, "refresh", refresh)  # noqa: B010 (a method, replaced on the class)

    def __init__(self, *, site: Site, limits: Limits | None, clock: Callable[[], datetime]) -> None:
        self._site = site
        self._limits = limits or Limits()
        super().__init__(clock=clock)
        self._sync_frame = SyncFrame()
        self._pointing = PointingCorrection()
        self._model_frame = ModelFrame(equatorial=False, latitude_deg=math.nan)
        """The pointing model's frame as last given (a NaN latitude: none yet)."""

    @property
    def site(self) -> Site:
        return self._site

    @property
    def limits(self) -> Limits:
        return self._limits

    @limits.setter
    def limits(self, limits: Limits) -> None:
        self._limits = limits

    @property
    def pointing(self) -> PointingCorrection:
        """The syncs kept on the PC and the pointing model every reading and goto goes through
        (:mod:`scopelink.mount.pointing`)."""
        return self._pointing

    def keep_pointing_in(self, memory: DeviceMemory) -> None:
        """Keep the PC-side syncs in ``memory`` (restored now, saved on every change)."""
        self._pointing.attach(memory, aligned=self.state.aligned if self.state.connected else None)
        self._pointing.recheck(self._sync_frame.reach_deg, self._limits.max_sync_deg)
        self.pointing_changed()

    def pointing_changed(self) -> None:
        """Publish the current state again, its position corrected by the changed
        :attr:`pointing` (nothing while not connected: the last reading would claim it is)."""
        again = self._pointing.recorrected(self.state, self._site)
        if again is not None:
            self._publish(again)

    def _corrected(self, state: MountState) -> MountState:
        equatorial = self.capabilities.alignment_mode is not AlignmentMode.ALT_AZ
        frame = self._model_frame
        if frame.equatorial is not equatorial or frame.latitude_deg != self._site.latitude_deg:
            # Once per change of the mount's kind or the site (not per reading).
            frame = self._model_frame = ModelFrame(equatorial, self._site.latitude_deg)
        self._pointing.set_frame(frame)
        self._pointing.observe_alignment(state)
        return self._pointing.correct(state, self._site)

    def observed_altaz(self, ra_j2000_hours: float, dec_j2000_deg: float) -> tuple[float, float]:
        """Observed (refracted) altitude and azimuth of a J2000 position now, at this site."""
        return j2000_to_observed(ra_j2000_hours, dec_j2000_deg, self.now(), self._site)

    @property
    def sync_frame(self) -> SyncFrame:
        """The net correction syncs through this object have made (axis degrees)."""
        return self._sync_frame

    def _sync_frame_after(
        self, ra_j2000_hours: float, dec_j2000_deg: float, state: MountState
    ) -> SyncFrame:
        """The net correction after a sync to this position from ``state`` (the simulator,
        which knows its counters, says exactly)."""
        altaz = None
        if self.capabilities.alignment_mode is AlignmentMode.ALT_AZ:
            altaz = self.observed_altaz(ra_j2000_hours, dec_j2000_deg)
        return self._sync_frame.after_sync(ra_j2000_hours, dec_j2000_deg, state, altaz)
