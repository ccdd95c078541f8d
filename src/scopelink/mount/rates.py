"""Custom tracking rates: offsets from the tracking mode's rate in RA and Dec (docs/tracking.md).

``Mount.set_tracking_rates(ra_arcsec_per_s, dec_arcsec_per_s)`` makes the mount follow a target
whose J2000 RA and Dec change at these rates while tracking is on (a comet, the Moon's motion in
Dec). Units, chosen so both axes read alike and nothing depends on the clock's kind:

- ``ra_arcsec_per_s``: arcseconds *of right ascension* (15″ = one second of RA; a coordinate
  rate, not a great-circle one: multiply by cos Dec for the speed on the sky) per SI second,
  positive when RA grows (the target drifts east, so the polar axis turns slower than sidereal);
- ``dec_arcsec_per_s``: arcseconds of declination per SI second, positive northwards.

ASCOM's ``RightAscensionRate`` is in seconds of RA per *sidereal* second and ``DeclinationRate``
in arcseconds per SI second: :func:`ra_rate_from_ascom` and :func:`ra_rate_to_ascom` convert.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from typing import Protocol, runtime_checkable

from scopelink.astro import (
    KING_RATE_DEG_S,
    LUNAR_RATE_DEG_S,
    SIDEREAL_DAY_S,
    SIDEREAL_RATE_DEG_S,
    SOLAR_RATE_DEG_S,
)
from scopelink.mount.deadman import MotionClient, current_client
from scopelink.mount.errors import InvalidValueError, NotSupportedError
from scopelink.mount.types import Capabilities, GuideDirection, MountState, TrackingMode

__all__ = [
    "SI_SECONDS_PER_SIDEREAL_SECOND",
    "GuideRates",
    "GuideShifts",
    "LoopPulses",
    "RateKeeper",
    "RateLoopStatistics",
    "RatesSetter",
    "TrackingRates",
    "check_tracking_rates",
    "clamp_rate",
    "ra_rate_from_ascom",
    "ra_rate_to_ascom",
    "root_mean_square",
    "tracking_rate_deg_s",
]

logger = logging.getLogger(__name__)

SI_SECONDS_PER_SIDEREAL_SECOND = SIDEREAL_DAY_S / 86400.0
"""0.99726957: ASCOM's "number of UTC seconds in a sidereal second"."""

OFFSET_MODES = frozenset(
    {TrackingMode.SIDEREAL, TrackingMode.LUNAR, TrackingMode.SOLAR, TrackingMode.KING}
)
"""The tracking modes custom rates are added to (equatorial tracking at a set rate; not the
alt-az or PEC modes of a hand control, which follow the sky their own way)."""


def clamp_rate(value: float, limit: float) -> float:
    """``value`` limited to ±``limit`` (a rate loop's correction, a follower's rates). Not for
    NaN, which comes out as ``+limit``: callers check for numbers first."""
    return max(-limit, min(limit, value))


def root_mean_square(values: Sequence[float]) -> float:
    """The RMS of ``values`` (a tracking error's figure); NaN when there are none."""
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else math.nan


def tracking_rate_deg_s(mode: TrackingMode) -> float:
    """How fast the polar axis turns in ``mode`` (sidereal unless lunar, solar or King)."""
    rates = {
        TrackingMode.LUNAR: LUNAR_RATE_DEG_S,
        TrackingMode.SOLAR: SOLAR_RATE_DEG_S,
        TrackingMode.KING: KING_RATE_DEG_S,
    }
    return rates.get(mode, SIDEREAL_RATE_DEG_S)


@dataclass(frozen=True, slots=True)
class TrackingRates:
    """Offsets of the tracked J2000 position, in arcsec per SI second (module docstring)."""

    ra_arcsec_per_s: float = 0.0
    dec_arcsec_per_s: float = 0.0

    @property
    def zero(self) -> bool:
        return self.ra_arcsec_per_s == 0.0 and self.dec_arcsec_per_s == 0.0

    def plus_mode(self, mode: TrackingMode) -> TrackingRates:
        """These rates plus the RA drift of ``mode`` against the stars (lunar: 0.356″/s)."""
        drift = (SIDEREAL_RATE_DEG_S - tracking_rate_deg_s(mode)) * 3600.0
        return TrackingRates(self.ra_arcsec_per_s + drift, self.dec_arcsec_per_s)

    @property
    def ra_hours_per_s(self) -> float:
        return self.ra_arcsec_per_s / (15.0 * 3600.0)

    @property
    def dec_deg_per_s(self) -> float:
        return self.dec_arcsec_per_s / 3600.0


def ra_rate_from_ascom(seconds_of_ra_per_sidereal_s: float) -> float:
    """ASCOM ``RightAscensionRate`` (s of RA per sidereal s) in arcsec of RA per SI second."""
    return seconds_of_ra_per_sidereal_s * 15.0 / SI_SECONDS_PER_SIDEREAL_SECOND


def ra_rate_to_ascom(ra_arcsec_per_s: float) -> float:
    """Arcsec of RA per SI second as ASCOM's ``RightAscensionRate``."""
    return ra_arcsec_per_s * SI_SECONDS_PER_SIDEREAL_SECOND / 15.0


def check_tracking_rates(
    capabilities: Capabilities, ra_arcsec_per_s: float, dec_arcsec_per_s: float
) -> TrackingRates:
    """The rates, or a one-line refusal: finite, within the mount's
    ``max_tracking_offset_arcsec_s``, and only on a mount that can set them."""
    limit = capabilities.max_tracking_offset_arcsec_s
    for name, value in (("RA", ra_arcsec_per_s), ("Dec", dec_arcsec_per_s)):
        if not isinstance(value, int | float) or isinstance(value, bool):
            raise InvalidValueError(f"{name} tracking rate must be a number, not {value!r}")
        if not math.isfinite(value):
            raise InvalidValueError(f"{name} tracking rate {value} is not a finite number")
    rates = TrackingRates(float(ra_arcsec_per_s), float(dec_arcsec_per_s))
    if rates.zero:
        return rates
    if limit <= 0.0:
        raise NotSupportedError("this mount cannot track at custom rates")
    for name, value in (("RA", rates.ra_arcsec_per_s), ("Dec", rates.dec_arcsec_per_s)):
        if abs(value) > limit:
            raise InvalidValueError(
                f"{name} tracking rate {value:g}″/s must lie within ±{limit:g}″/s on this mount"
            )
    return rates


class RatesSetter(Protocol):
    """What :class:`RateKeeper` needs of the mount: its state and the checked setter."""

    @property
    def state(self) -> MountState: ...

    async def set_tracking_rates(self, ra_arcsec_per_s: float, dec_arcsec_per_s: float) -> None: ...


class RateKeeper:
    """The custom rates in force on one mount, and who set them (the dead-man calls
    :meth:`left`, which resets them to zero: a custom rate never outlives its client)."""

    def __init__(self, mount: RatesSetter) -> None:
        self._mount = mount
        self.rates = TrackingRates()
        self.owner: MotionClient | None = None

    def set(self, rates: TrackingRates) -> None:
        self.rates = rates
        self.owner = None if rates.zero else current_client()

    async def left(self, client: MotionClient) -> None:
        """``client`` has gone: its custom rates go back to zero (the mode's own rate)."""
        if self.owner is client and not self.rates.zero and self._mount.state.connected:
            logger.warning("%s went away with custom tracking rates: back to zero", client.name)
            await self._mount.set_tracking_rates(0.0, 0.0)


ERRORS_KEPT = 20_000
"""A rate loop keeps the errors of its last 20 000 readings (about 15 minutes of polls)."""


@dataclass
class RateLoopStatistics:
    """A driver's closed rate loop (docs/tracking.md): the pointing error of every reading it
    used (arcsec on the sky), where and when it started, how many commands it sent."""

    errors_arcsec: list[float] = field(default_factory=list)
    started_at: datetime | None = None
    anchor: tuple[float, float] | None = None
    """The J2000 RA (h) and Dec (°) read at ``started_at``: the target is integrated from it."""
    commands: int = 0
    pulses: int = 0
    """Guide pulses added to the loop's rate (instead of ending it)."""

    def add_error(self, arcsec: float) -> None:
        """One reading's error; only the last ``ERRORS_KEPT`` are kept (a night's loop)."""
        self.errors_arcsec.append(arcsec)
        if len(self.errors_arcsec) > 2 * ERRORS_KEPT:
            del self.errors_arcsec[:-ERRORS_KEPT]

    def rms_after(self, skip: int) -> float:
        return root_mean_square(self.errors_arcsec[skip:])


@dataclass
class GuideShifts:
    """The guide pulses given while a rate loop runs, as a shift of its target: a pulse of
    ``duration_s`` at (RA, Dec) rates moves the target by rate x time, growing while the
    pulse runs, so the loop keeps the guider's correction instead of undoing it."""

    _pulses: list[list[float]] = field(default_factory=list)
    """[key, start, duration] on the loop's clock (s), RA rate (h/s), Dec rate (°/s)."""

    def add(
        self, key: int, start_s: float, duration_s: float, ra_h_s: float, dec_deg_s: float
    ) -> None:
        """A pulse from ``start_s``; one still running with the same ``key`` (its axis) is
        cut short there, as the new pulse replaces it."""
        self.cut(key, start_s)
        self._pulses.append([float(key), start_s, duration_s, ra_h_s, dec_deg_s])

    def cut(self, key: int, at_s: float) -> None:
        """End the pulses of ``key`` at ``at_s`` (a pulse stopped early)."""
        for pulse in self._pulses:
            if pulse[0] == key and pulse[1] + pulse[2] > at_s:
                pulse[2] = max(0.0, at_s - pulse[1])

    def at(self, t_s: float) -> tuple[float, float]:
        """The target's shift (RA hours, Dec degrees) at ``t_s`` on the loop's clock."""
        ra = dec = 0.0
        for _, start, duration, ra_rate, dec_rate in self._pulses:
            done = max(0.0, min(duration, t_s - start))
            ra += ra_rate * done
            dec += dec_rate * done
        return ra, dec

    def rates_at(self, t_s: float) -> tuple[float, float]:
        """The pulses' (RA h/s, Dec °/s) rate at ``t_s`` (those still running)."""
        ra = dec = 0.0
        for _, start, duration, ra_rate, dec_rate in self._pulses:
            if start <= t_s < start + duration:
                ra += ra_rate
                dec += dec_rate
        return ra, dec


@runtime_checkable
class GuideRates(Protocol):
    """A mount whose pulse-guide rates can be set (ASCOM's GuideRateRightAscension and
    GuideRateDeclination): the SynScan driver (its rate slews) and the Sky Tracker (``K``)."""

    @property
    def guide_rates_deg_s(self) -> tuple[float, float]:
        """(RA, Dec) guide rates in degrees per second, as pulses use them."""

    async def set_guide_rates(self, ra_deg_s: float, dec_deg_s: float) -> None:
        """Set both; a rate the mount cannot give raises ``InvalidValueError``, nothing set."""


class LoopPulses(Protocol):
    """A driver with a custom-rate loop that guide pulses join (docs/tracking.md)."""

    _loop_taken: bool
    _loop_joining: bool
    """Set while a pulse goes out: its ``_motion_commanded`` must not end the loop."""

    @property
    def custom_rates_running(self) -> bool: ...


async def pulse_joining_loop(
    mount: LoopPulses,
    pulse_guide: Callable[[GuideDirection, int], Awaitable[None]],
    direction: GuideDirection,
    duration_ms: int,
) -> bool:
    """``pulse_guide`` (the Mount's, checked) with the loop's joining flag set while the loop runs
    and is in charge, so the pulse is added to the loop instead of ending it; whether it joined."""
    if not mount.custom_rates_running or mount._loop_taken:
        await pulse_guide(direction, duration_ms)
        return False
    mount._loop_joining = True
    try:
        await pulse_guide(direction, duration_ms)
    finally:
        mount._loop_joining = False
    return True
