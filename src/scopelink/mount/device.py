"""What a driver implements: the protocol-specific half of a :class:`~scopelink.mount.Mount`.

A driver (or the simulator) subclasses ``Mount`` and fills in what its device supports: who
answered (:attr:`MountDevice.capabilities`, :attr:`MountDevice.identity`), the connection and a
read of the device (:meth:`connect`, :meth:`disconnect`, :meth:`refresh`), and the underscore
commands below. They are called only after ``Mount`` has validated the arguments and checked the
limits; the ones a device lacks raise :class:`NotSupportedError`, which front ends report as "not
implemented".
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from datetime import datetime

from scopelink.astro import PierSide, Site, destination_side_of_pier
from scopelink.mount.errors import NotSupportedError
from scopelink.mount.rates import TrackingRates
from scopelink.mount.types import (
    Capabilities,
    GuideDirection,
    Identity,
    MountAxis,
    MountState,
    TrackingMode,
)

__all__ = ["MountDevice"]


class MountDevice(ABC):
    """The device behind a mount: what it is, how to reach it, and its unchecked commands."""

    @property
    @abstractmethod
    def capabilities(self) -> Capabilities:
        """What this mount can do."""

    @property
    @abstractmethod
    def identity(self) -> Identity:
        """Who answered on the link."""

    @abstractmethod
    async def connect(self) -> None:
        """Open the link and identify the device."""

    @abstractmethod
    async def disconnect(self) -> None:
        """Stop using the device and close the link; motion is stopped where the protocol allows."""

    @abstractmethod
    async def refresh(self) -> MountState:
        """Read the device now and return (and cache) a fresh state."""

    async def _goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        raise NotSupportedError("this mount cannot go to equatorial coordinates")

    async def _goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        raise NotSupportedError("this mount cannot go to horizontal coordinates")

    async def _sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        raise NotSupportedError("this mount cannot sync")

    async def _abort(self) -> None:
        raise NotSupportedError("this mount cannot abort a slew")

    async def _move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        raise NotSupportedError("this mount cannot move an axis at a rate")

    async def _pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        raise NotSupportedError("this mount cannot pulse-guide")

    async def _set_tracking(self, mode: TrackingMode) -> None:
        raise NotSupportedError("this mount cannot change tracking")

    async def _set_tracking_rates(self, rates: TrackingRates) -> None:
        raise NotSupportedError("this mount cannot track at custom rates")

    async def _park(self) -> None:
        raise NotSupportedError("this mount cannot park")

    async def _unpark(self) -> None:
        raise NotSupportedError("this mount cannot unpark")

    async def _set_site(self, site: Site) -> None:  # noqa: B027 - optional hook, no-op by default
        """Devices that store no site keep the default: the site is used on the PC side only."""

    async def _set_time(self, utc: datetime) -> None:
        raise NotSupportedError("this mount keeps no time")

    # --- the pier side of a goto (meridian limits: scopelink.mount.meridian) --------------------

    can_choose_pier_side: bool = False
    """Whether a goto can be told which side of the pier to land on (``_goto_*_on``); a hand
    control that picks its side itself cannot (a SynScan hand control)."""

    def _predicted_pier_side(self, ha_hours: float, dec_deg: float) -> PierSide:
        """The side of the pier the device's own goto to (``ha_hours``, ``dec_deg``) lands on:
        by default ASCOM's destination side (the meridian decides)."""
        return destination_side_of_pier(ha_hours)

    async def _goto_equatorial_on(
        self, ra_j2000_hours: float, dec_j2000_deg: float, side: PierSide
    ) -> None:
        raise NotSupportedError("this mount cannot be told the pier side of a goto")

    async def _goto_horizontal_on(self, alt_deg: float, az_deg: float, side: PierSide) -> None:
        raise NotSupportedError("this mount cannot be told the pier side of a goto")
