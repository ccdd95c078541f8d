"""Guide pulses while the SynScan PC loop runs, and the guide rates (docs/tracking.md, "Guide
pulses while the loop runs").

A pulse while custom rates are in force joins the loop instead of ending it: its guide rate is
added to the loop's rate on its axis for its duration, and the loop's target moves with it
(``GuideShifts``), so the loop keeps the guider's correction instead of undoing it.
"""

from __future__ import annotations

import asyncio
import logging
from dataclasses import replace

from scopelink.astro import PierSide
from scopelink.drivers.synscan.base import MAX_GUIDE_RATE_DEG_S
from scopelink.drivers.synscan.rates import SynScanRates
from scopelink.mount import GuideDirection, InvalidValueError, MountAxis, MountError
from scopelink.mount.rates import pulse_joining_loop

__all__ = ["SynScanLoopPulses"]

logger = logging.getLogger(__name__)


class SynScanLoopPulses(SynScanRates):
    """Guide pulses that join the PC loop, and the settable guide rates (module docstring)."""

    _guide_rate_dec_deg_s: float | None = None

    @property
    def guide_rates_deg_s(self) -> tuple[float, float]:
        """(RA, Dec) pulse-guide rates (°/s): ``guide_rate_deg_s`` unless Dec's was set apart."""
        dec = self._guide_rate_dec_deg_s
        return self.guide_rate_deg_s, self.guide_rate_deg_s if dec is None else dec

    async def set_guide_rates(self, ra_deg_s: float, dec_deg_s: float) -> None:
        """Pulse-guide rates (°/s) in RA and Dec, each within (0, 10x sidereal]: the hand
        control's rate slews take ¼″/s steps (the PC times the pulses)."""
        for name, value in (("RA", ra_deg_s), ("Dec", dec_deg_s)):
            if not (isinstance(value, int | float) and 0.0 < value <= MAX_GUIDE_RATE_DEG_S):
                raise InvalidValueError(
                    f"{name} guide rate {value!r}°/s must lie in (0, {MAX_GUIDE_RATE_DEG_S:.5f}] "
                    "(10x sidereal)"
                )
        self.guide_rate_deg_s = float(ra_deg_s)
        self._guide_rate_dec_deg_s = float(dec_deg_s)

    async def pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        """As :meth:`Mount.pulse_guide`; while the loop runs the pulse is added to it (its
        guide rate on top of the loop's, the target moved along: docs/tracking.md)."""
        await pulse_joining_loop(self, super().pulse_guide, direction, duration_ms)

    async def _pulse_into_loop(
        self, axis: MountAxis, axis_rate_deg_s: float, duration_ms: int
    ) -> None:
        """The guide rate on ``axis`` added to the loop's for ``duration_ms`` (PC time), and the
        loop's target moved along with it, so the loop keeps the correction."""
        statistics, shifts = self.rate_loop_statistics, self._loop_shifts
        assert statistics is not None
        assert shifts is not None
        hemisphere = 1.0 if self.site.latitude_deg >= 0 else -1.0
        arcsec = axis_rate_deg_s * 3600.0
        if axis is MountAxis.PRIMARY:  # the polar axis turning faster: RA decreasing
            ra_rate, dec_rate = -hemisphere * arcsec / 54000.0, 0.0
        else:
            dec_sign = -hemisphere if self._pier_side is PierSide.WEST else hemisphere
            ra_rate, dec_rate = 0.0, dec_sign * arcsec / 3600.0
        previous = self._pulses.pop(axis, None)
        if previous is not None:
            previous.cancel()
        t, ratio = self._loop_time_s()
        shifts.add(axis.value, t, duration_ms / 1000.0 * ratio, ra_rate, dec_rate)
        statistics.pulses += 1
        await self._drive_now(statistics)
        self._pulses[axis] = asyncio.create_task(
            self._end_loop_pulse(axis, duration_ms / 1000.0), name=f"end guide pulse {axis.name}"
        )
        self._publish(replace(self.state, pulse_guiding=True))

    async def _end_loop_pulse(self, axis: MountAxis, duration_s: float) -> None:
        try:
            await asyncio.sleep(duration_s)
            statistics = self.rate_loop_statistics
            if statistics is not None and self._loop_still_ours():
                assert self._loop_shifts is not None
                self._loop_shifts.cut(axis.value, self._loop_time_s()[0])
                await self._drive_now(statistics)
        except MountError as error:
            logger.warning("%s: ending a guide pulse in the loop: %s", self.wire.name, error)
        finally:
            if self._pulses.get(axis) is asyncio.current_task():
                del self._pulses[axis]
            if not self._pulses:
                self._publish(replace(self.state, pulse_guiding=False))
