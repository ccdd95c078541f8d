"""What every part of the SynScan driver stands on: construction, who the device is, and every
exchange (owed stops first, see ``stops.py``).

The driver is one class per concern, each building on the one before: ``base`` (this),
``connection`` (open, identify, reconnect), ``polling`` (the state), ``mount`` (the commands).
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
from collections.abc import Callable, Iterator
from datetime import datetime
from typing import TypeVar

from scopelink.astro import SIDEREAL_RATE_DEG_S, PierSide, Site
from scopelink.drivers.common import LinkFactory, Reconnection, link_factory
from scopelink.drivers.synscan.exchange import DEFAULT_TIMEOUT_S, SynScanWire
from scopelink.drivers.synscan.identify import HandControlInfo, synscan_tracking
from scopelink.drivers.synscan.settling import SettleDetector
from scopelink.drivers.synscan.stops import OwedStops
from scopelink.mount import (
    AlignmentMode,
    Capabilities,
    DeviceError,
    Identity,
    Limits,
    Mount,
    MountAxis,
    ParkPosition,
    Priority,
    TrackingMode,
    utc_now,
)
from scopelink.protocol.synscan import (
    Ack,
    AnyCommand,
    AnyReply,
    Axis,
    CancelGoto,
    FixedRateSlew,
    PassthroughFailed,
    SetTrackingMode,
)

__all__ = ["DEFAULT_GUIDE_RATE_DEG_S", "SynScanBase"]

logger = logging.getLogger(__name__)

DEFAULT_GUIDE_RATE_DEG_S = 0.5 * SIDEREAL_RATE_DEG_S
"""Guide pulses move at half the sidereal rate, the usual autoguider setting."""

AXES = {MountAxis.PRIMARY: Axis.AZM_RA, MountAxis.SECONDARY: Axis.ALT_DEC}

R = TypeVar("R", bound=AnyReply)


def rate_zero(axis: MountAxis) -> FixedRateSlew:
    """Rate 0 on ``axis``: stops a fixed- or variable-rate slew (see the protocol notes)."""
    return FixedRateSlew(AXES[axis], positive=True, rate=0)


MAX_GUIDE_RATE_DEG_S = 10.0 * SIDEREAL_RATE_DEG_S
"""The fastest pulse-guide rate the driver takes (10x sidereal)."""


class SynScanBase(Mount):
    """The SynScan driver's construction, identity and exchanges (see :class:`SynScanMount`)."""

    syncs_on_device = False
    """A hand control's sync is one local offset, refused beyond ~7° and before an alignment:
    scopelink keeps every sync itself and fits a pointing model (docs/pointing.md)."""

    def __init__(
        self,
        link: str | LinkFactory,
        *,
        site: Site,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        limits: Limits | None = None,
        clock: Callable[[], datetime] = utc_now,
        park_position: ParkPosition | None = None,
        guide_rate_deg_s: float = DEFAULT_GUIDE_RATE_DEG_S,
        utc_offset_hours: int = 0,
        altaz_settle_timeout_s: float = 300.0,
        name: str | None = None,
    ) -> None:
        super().__init__(site=site, limits=limits, clock=clock, park_position=park_position)
        factory, name = link_factory(link, name=name, unnamed="SynScan link")
        if not 0 < guide_rate_deg_s <= MAX_GUIDE_RATE_DEG_S:
            raise ValueError(f"guide rate {guide_rate_deg_s}°/s must lie in (0, 10x sidereal]")
        if not -12 <= utc_offset_hours <= 14:
            raise ValueError(f"UTC offset {utc_offset_hours} h must lie in [-12, 14]")
        self.wire = SynScanWire(factory, name=name, timeout_s=timeout_s)
        self.guide_rate_deg_s = guide_rate_deg_s
        self.utc_offset_hours = utc_offset_hours
        self.altaz_settle_timeout_s = altaz_settle_timeout_s
        self.info: HandControlInfo | None = None
        """What the hand control said at connect (firmware, model, motor controller versions)."""
        self._identity = Identity("synscan", "", link=name)
        self._capabilities = Capabilities(alignment_mode=AlignmentMode.GERMAN_POLAR)
        self._connected = False
        self._aligned = False
        self._parked = False
        self._park_target: ParkPosition | None = None
        """Where the last park goto went (AtPark once it has ended there)."""
        self._tracking = TrackingMode.OFF
        self._pier_side = PierSide.UNKNOWN
        self._goto_running = False
        self._settle: SettleDetector | None = None
        self._axis_rates: dict[MountAxis, float] = {}
        self._site_mismatch = ""
        """Set when the hand control's site (``w``) is not ours: alt/az computed here would then
        disagree with where it points. Cleared by ``set_site``."""
        self._cycles_since_full_read = 0
        self._epoch_at_full_read = -1
        self._motion_epoch = 0
        """Counts gotos and aborts: a poll that overlapped one must not judge it by its L."""
        self._pulses: dict[MountAxis, asyncio.Task[None]] = {}
        self._owed = OwedStops()
        """Stops a failed exchange left unconfirmed: sent before anything else once the wire
        works again (see ``stops.py``). Kept across disconnect: the next connect sends them."""
        self._paying = False
        self._failures_at_full_read = 0
        self._reidentify = False
        """The link was lost (closed, or the device silent past ``stale_after_s``): the next
        poll opens it anew and identifies the device again before reading."""
        self._identified_on = -1
        """``wire.statistics.reconnects`` when the device was last identified: a link the wire
        reopened by itself gets the device identified again too."""
        self._reconnection = Reconnection()

    @property
    def capabilities(self) -> Capabilities:
        return self._capabilities

    @property
    def identity(self) -> Identity:
        return self._identity

    @property
    def timeout_s(self) -> float:
        return self.wire.timeout_s

    @property
    def engaged(self) -> bool:
        return self._connected

    def _line_bytes(self) -> tuple[int, int]:
        return self.wire.statistics.bytes_sent, self.wire.statistics.bytes_received

    def _standing_problems(self) -> tuple[str, ...]:
        # An unconfirmed stop stays named while polls fail (no motion is claimed meanwhile).
        return (self._owed.describe(),) if self._owed else ()

    async def _stop_at_once(self, commands: list[AnyCommand]) -> None:
        """The first, unconfirmed, part of a stop: see ``SynScanWire.stop_at_once``. A failure
        here is left to the confirming exchanges that follow (they recover, or raise)."""
        try:
            await self.wire.stop_at_once(commands)
        except DeviceError as error:
            logger.warning("%s: a stop could not be written at once: %s", self.wire.name, error)

    async def _send_rate_zero(self, axis: MountAxis) -> None:
        reply = await self._wire_ask(rate_zero(axis))
        if isinstance(reply, PassthroughFailed):
            logger.warning("%s: stop of the %s axis not acknowledged", self.wire.name, axis.name)

    async def _resume_tracking(self) -> None:
        """Re-send the tracking mode: on the hand control a rate slew overrides tracking."""
        if self._tracking is not TrackingMode.OFF:
            await self._ask(SetTrackingMode(synscan_tracking(self._tracking)), Ack)

    @contextlib.contextmanager
    def _stops_owed_on_failure(
        self, *, cancel_goto: bool = False, axes: set[MountAxis] | None = None
    ) -> Iterator[None]:
        """If the exchanges inside fail, owe the stops that undo them (see ``stops.py``)."""
        try:
            yield
        except DeviceError as error:
            self._owe_stops(cancel_goto=cancel_goto, axes=axes or set(), cause=str(error))
            raise

    def _owe_stops(self, *, cancel_goto: bool = False, axes: set[MountAxis], cause: str) -> None:
        self._owed.owe(cancel_goto=cancel_goto, axes=axes, cause=cause)
        logger.warning("%s: %s", self.wire.name, self._owed.describe())
        problems = (self._owed.describe(),)
        self._publish(dataclasses.replace(self.state, slewing=True, problems=problems))

    async def _pay_owed_stops(self) -> None:
        """Send the owed stops, holding the wire, before the exchange that found them owed."""
        async with self.wire.exclusive():
            if not self._owed or self._paying:
                return
            self._paying = True
            try:
                if self._owed.cancel_goto:
                    await self._ask(CancelGoto(), Ack)
                    self._owed.cancel_goto = False
                    self._motion_epoch += 1
                    self._goto_running = False
                    self._settle = None
                for axis in sorted(self._owed.axes, key=lambda axis: axis.value):
                    await self._send_rate_zero(axis)
                    self._owed.axes.discard(axis)
                    self._axis_rates.pop(axis, None)
                await self._resume_tracking()
            finally:
                self._paying = False
            logger.warning("%s: the owed stops were sent (%s)", self.wire.name, self._owed.cause)
            self._owed.clear()

    async def _wire_ask(
        self,
        command: AnyCommand,
        priority: Priority = Priority.COMMAND,
        *,
        meanwhile: Callable[[], object] | None = None,
    ) -> AnyReply:
        """Every exchange of the driver: owed stops go first (see ``stops.py``)."""
        if self._owed and not self._paying:
            await self._pay_owed_stops()
        return await self.wire.ask(command, priority, meanwhile=meanwhile)

    async def _ask(
        self,
        command: AnyCommand,
        expected: type[R],
        priority: Priority = Priority.COMMAND,
        *,
        meanwhile: Callable[[], object] | None = None,
    ) -> R:
        reply = await self._wire_ask(command, priority, meanwhile=meanwhile)
        if not isinstance(reply, expected):
            raise DeviceError(
                f"{self.wire.name}: {command.describe()!r} answered {reply.describe()!r}"
            )
        return reply

    async def _ask_passthrough(self, command: AnyCommand) -> None:
        reply = await self._wire_ask(command)
        if isinstance(reply, PassthroughFailed):
            raise DeviceError(
                f"{command.describe()!r}: the motor controller did not answer the hand control "
                "(failed passthrough)"
            )
