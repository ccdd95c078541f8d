"""The Sky Tracker's guide speeds: ``K`` as the driver's ``set_guide_speed`` and as the Mount's
guide rates (``scopelink.mount.rates.GuideRates``, Alpaca's GuideRate*), used by guide pulses."""

from __future__ import annotations

import math

from scopelink.mount import InvalidValueError

from .motion import GUIDE_SPEED_MAX_ARCSEC_S
from .polling import SkyTrackerPolling

__all__ = ["SkyTrackerGuiding"]


class SkyTrackerGuiding(SkyTrackerPolling):
    """Guide speeds (see :class:`SkyTrackerMount`)."""

    async def set_guide_speed(self, azimuth_arcsec_s: int, elevation_arcsec_s: int) -> None:
        """``K`` (confirmed with ``k``): the guide speed of pulses and GUIDE-mode arrows."""
        for value in (azimuth_arcsec_s, elevation_arcsec_s):
            if not 1 <= value <= GUIDE_SPEED_MAX_ARCSEC_S:
                raise InvalidValueError(f"guide speed {value} arcsec/s is not 1-255")
        self._require_line()
        self._pulse_speeds = (azimuth_arcsec_s, elevation_arcsec_s)
        async with self._buttons:
            await self._set_guide_speeds(self._pulse_speeds)

    @property
    def guide_rates_deg_s(self) -> tuple[float, float]:
        """(RA, Dec) pulse-guide rates (°/s): the ``K`` speeds of azimuth (east/west pulses)
        and elevation (north/south), which the box takes in whole arcsec/s of the axis."""
        azimuth, elevation = self._pulse_speeds
        return azimuth / 3600.0, elevation / 3600.0

    async def set_guide_rates(self, ra_deg_s: float, dec_deg_s: float) -> None:
        """``K``: the RA rate for azimuth, the Dec rate for elevation, rounded to whole arcsec/s
        (1-255)."""
        speeds = []
        for name, value in (("RA", ra_deg_s), ("Dec", dec_deg_s)):
            arcsec = value * 3600.0 if isinstance(value, int | float) else math.nan
            if not 0.5 <= arcsec < GUIDE_SPEED_MAX_ARCSEC_S + 0.5:
                raise InvalidValueError(
                    f"{name} guide rate {value!r}°/s must lie within 1-{GUIDE_SPEED_MAX_ARCSEC_S}"
                    "″/s on a Sky Tracker (its 'K' speed, whole arcsec/s)"
                )
            speeds.append(round(arcsec))
        await self.set_guide_speed(speeds[0], speeds[1])
