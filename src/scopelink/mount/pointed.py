"""The Mount's frame: its site and limits, and the readings corrected by the syncs kept on the PC
(:mod:`scopelink.mount.pointing`) — every published state goes through
:meth:`PointedMount._corrected`, and every driver's ``refresh`` returns its reading corrected, so
no front end ever sees an uncorrected position. Also the net frame change that syncs sent to the
device have made (:mod:`scopelink.mount.syncs`).

One pass per reading (issue #14): the model's frame is judged again only when the mount's
capabilities or the site change (each an immutable object, replaced on change), and the reading a
driver's ``refresh`` returns, published a moment before, is not corrected a second time: its
correction is kept, with the model's generation and the site it was made under.

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
from scopelink.mount.types import AlignmentMode, Capabilities, MountState

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
                state = await original(self)
                # The reading the driver has just published: its correction as _publish made
                # it, unless the model or the site changed since (identity checks only).
                last = self._last_correction
                if (
                    last[0] is state
                    and last[2] == self._pointing.generation
                    and last[3] is self._site
                ):
                    return last[1]
                return self._corrected(state)

            setattr(cls, "refresh", refresh)  # noqa: B010 (a method, replaced on the class)

    def __init__(self, *, site: Site, limits: Limits | None, clock: Callable[[], datetime]) -> None:
        self._site = site
        self._limits = limits or Limits()
        super().__init__(clock=clock)
        self._sync_frame = SyncFrame()
        self._pointing = PointingCorrection()
        self._model_frame = ModelFrame(equatorial=False, latitude_deg=math.nan)
        """The pointing model's frame as last given (a NaN latitude: none yet)."""
        self._frame_for: tuple[Capabilities | None, Site | None] = (None, None)
        """The capabilities and site the frame was last judged for (identity: both immutable)."""
        self._last_correction: tuple[MountState | None, MountState, int, Site | None] = (
            None,
            self.state,
            -1,
            None,
        )
        """The last reading :meth:`_corrected` was given, its answer, the model's generation
        and the site then."""

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
        """``state`` corrected by :attr:`pointing` (which also watches it for a new alignment)."""
        site = self._site
        pointing = self._pointing
        capabilities = self.capabilities
        frame_for = self._frame_for
        if frame_for[0] is not capabilities or frame_for[1] is not site:
            # Once per change of the mount's kind or the site (not per reading).
            self._frame_for = (capabilities, site)
            equatorial = capabilities.alignment_mode is not AlignmentMode.ALT_AZ
            frame = self._model_frame
            if frame.equatorial is not equatorial or frame.latitude_deg != site.latitude_deg:
                frame = self._model_frame = ModelFrame(equatorial, site.latitude_deg)
            pointing.set_frame(frame)
        corrected = pointing.observe(state, site)
        self._last_correction = (state, corrected, pointing.generation, site)
        return corrected

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
