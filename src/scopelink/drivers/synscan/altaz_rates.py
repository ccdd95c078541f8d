"""Custom tracking rates on an alt-az SynScan mount (AZ GTi, Virtuoso...): the PC loop of
``rates.py`` driving the azimuth and altitude axes (docs/tracking.md, "The SynScan alt-az loop").

The hand control's alt-az tracking follows a fixed point of the sky and takes no offset, so while
custom rates are in force its tracking is turned off (``T 0``), as on an equatorial mount, and
the PC turns both axes with variable-rate slews (``P 3 16|17 6|7 hi lo``; positive: azimuth
growing, altitude growing, the driver's ``move_axis`` convention). Each axis is driven at

- **feed-forward**: the rate of the target's observed azimuth or altitude now, a central
  difference over ``FEED_FORWARD_STEP_S`` of the target integrated at the custom rates (the
  sky's turning and the target's own motion together), plus
- **correction**: ``LOOP_GAIN_PER_S`` x the error against the reading, in axis degrees (the
  target's alt/az minus the reading's, both at the reading's time), clamped to
  ``MAX_CORRECTION_ARCSEC_S`` and rounded to the ¼″/s step, as on an equatorial mount.

Near the zenith the azimuth axis needs the sky's speed / cos(alt): beyond the hand control's top
speed (``MAX_SLEW_RATE_DEG_S``, 3.34°/s) the axis is held at it and the state's problems say the
scope falls behind, until the wanted rate is within reach again.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from datetime import timedelta

from scopelink.astro import j2000_to_observed, wrap_signed_degrees
from scopelink.drivers.synscan.identify import MAX_SLEW_RATE_DEG_S
from scopelink.drivers.synscan.loop_pulses import SynScanLoopPulses
from scopelink.drivers.synscan.loop_target import LoopTarget
from scopelink.drivers.synscan.rates import LOOP_GAIN_PER_S, MAX_CORRECTION_ARCSEC_S, quantised
from scopelink.mount import AlignmentMode, MountAxis, MountState
from scopelink.mount.rates import TrackingRates, clamp_rate

__all__ = ["FEED_FORWARD_STEP_S", "SynScanAltAzRates"]

logger = logging.getLogger(__name__)

FEED_FORWARD_STEP_S = 1.0
"""The feed-forward's central difference spans this much of the mount's clock (±0.5 s): the
Moon's alt/az rates change by < 0.001″/s over it, a satellite's by a few percent of the step's
curvature only."""


class SynScanAltAzRates(SynScanLoopPulses):
    """The PC loop on an alt-az mount's axes (module docstring); equatorial mounts keep the
    RA/Dec loop of :class:`~scopelink.drivers.synscan.rates.SynScanRates`."""

    _behind = ""
    """Why the loop cannot keep up now ("" while it can): added to the published states."""

    @property
    def _altaz_loop(self) -> bool:
        return self._capabilities.alignment_mode is AlignmentMode.ALT_AZ

    def _loop_errors(
        self, target: LoopTarget, state: MountState, dt: float
    ) -> tuple[float, float, float]:
        """Azimuth and altitude errors (axis degrees) of the reading against the target's
        observed place at the reading's time, and the error on the sky (arcsec)."""
        if not self._altaz_loop:
            return super()._loop_errors(target, state, dt)
        assert state.alt_deg is not None
        assert state.az_deg is not None
        alt, az = j2000_to_observed(*target.at(dt), state.read_at, self.site)
        az_error = wrap_signed_degrees(az - state.az_deg)
        alt_error = alt - state.alt_deg
        sky = 3600.0 * math.hypot(az_error * math.cos(math.radians(alt)), alt_error)
        return az_error, alt_error, sky

    def _axis_rates_for(
        self, target: LoopTarget, rates: TrackingRates, first_error: float, second_error: float
    ) -> dict[MountAxis, float]:
        """Azimuth and altitude axis rates (°/s): the target's alt/az rates now plus the
        corrections (module docstring)."""
        if not self._altaz_loop:
            return super()._axis_rates_for(target, rates, first_error, second_error)
        t, _ = self._loop_time_s()
        now, half = self.now(), FEED_FORWARD_STEP_S / 2.0
        alt0, az0 = j2000_to_observed(
            *target.at(t - half), now - timedelta(seconds=half), self.site
        )
        alt1, az1 = j2000_to_observed(
            *target.at(t + half), now + timedelta(seconds=half), self.site
        )
        feed_forward = {
            MountAxis.PRIMARY: wrap_signed_degrees(az1 - az0) / FEED_FORWARD_STEP_S,
            MountAxis.SECONDARY: (alt1 - alt0) / FEED_FORWARD_STEP_S,
        }
        errors = {MountAxis.PRIMARY: first_error, MountAxis.SECONDARY: second_error}
        limit = MAX_CORRECTION_ARCSEC_S / 3600.0
        wanted: dict[MountAxis, float] = {}
        behind: list[str] = []
        for axis, rate in feed_forward.items():
            axis_rate = rate + clamp_rate(LOOP_GAIN_PER_S * errors[axis], limit)
            if abs(axis_rate) > MAX_SLEW_RATE_DEG_S:
                behind.append("azimuth" if axis is MountAxis.PRIMARY else "altitude")
                axis_rate = math.copysign(MAX_SLEW_RATE_DEG_S, axis_rate)
            wanted[axis] = quantised(axis_rate * 3600.0) / 3600.0
        self._fall_behind(behind)
        return wanted

    def _fall_behind(self, axes: list[str]) -> None:
        """Say so (once per episode, and in every state meanwhile) when an axis would need more
        than the hand control's top speed."""
        was = self._behind
        self._behind = (
            f"custom tracking rates: the {' and '.join(axes)} axis would need more than "
            f"{MAX_SLEW_RATE_DEG_S:.2f}°/s (near the zenith): the scope falls behind"
            if axes
            else ""
        )
        if self._behind and not was:
            logger.warning("%s: %s", self.wire.name, self._behind)

    def _publish(self, state: MountState) -> None:
        if self._behind and self.custom_rates_running and self._behind not in state.problems:
            state = dataclasses.replace(state, problems=(*state.problems, self._behind))
        super()._publish(state)
