"""The Sky Commander digital setting circles: encoders in, J2000 coordinates and offsets out.

The encoders are the simulated mount's alt-az axes, read through :data:`EncoderReader`. The
Sky Commander adds its alignment offsets to them to know where the scope points on the sky.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path

from scopelink.astro import Site, j2000_to_observed, observed_to_j2000, wrap_signed_degrees
from scopelink.links import LinkClosedError
from scopelink.protocol.skytracker import (
    NEED_DATA,
    Acknowledge,
    Command,
    CommanderServer,
    ErrorEvent,
    LoadObject,
    OffsetsReply,
    PositionReply,
    RatesReply,
    ReadOffsets,
    ReadPosition,
    ReadRates,
    Realign,
)
from scopelink.protocol.skytracker.commander_messages import TEMPORARY_SLOT

from .objects import ObjectStore, StoredObject
from .port import DevicePort

logger = logging.getLogger(__name__)

EncoderReader = Callable[[], tuple[float, float]]
"""Returns the encoders' (altitude, azimuth) in degrees now; azimuth North = 0, East = 90."""

RATE_STEP_S = 60.0
"""Time step of the drive rate finite difference: the rates are degrees per minute."""
LINE_TIMEOUT_S = 1.0
"""An unfinished ``L`` line is dropped after this long without a byte."""


@dataclass(frozen=True, slots=True)
class Alignment:
    """What the Sky Commander adds to the encoder readings (degrees)."""

    altitude_deg: float = 0.0
    azimuth_deg: float = 0.0


class SkyCommander:
    """The Sky Commander's state and command handling (no I/O of its own; see :meth:`serve`).

    It starts **unaligned**, with zero offsets: it takes the encoders as level and North-zeroed,
    which the simulated axes are, so positions match the simulator until a realign (``N``)
    moves them. :attr:`aligned` tells whether ``N`` was used since power-on.
    """

    def __init__(
        self, encoders: EncoderReader, now: Callable[[], datetime], site: Site, store: ObjectStore
    ) -> None:
        self._encoders = encoders
        self._now = now
        self.site = site
        self.store = store
        self.alignment = Alignment()
        self.aligned = False
        self.current_object: StoredObject | None = None

    @classmethod
    def with_store_in(
        cls, directory: Path, encoders: EncoderReader, now: Callable[[], datetime], site: Site
    ) -> SkyCommander:
        """A Sky Commander whose object memory lives in ``directory``."""
        return cls(encoders, now, site, ObjectStore(directory))

    # --- where the scope points ---------------------------------------------------------------

    def sky_altaz_deg(self) -> tuple[float, float]:
        """Observed (altitude, azimuth) of the scope: encoders plus alignment."""
        altitude, azimuth = self._encoders()
        return (
            altitude + self.alignment.altitude_deg,
            (azimuth + self.alignment.azimuth_deg) % 360.0,
        )

    def position_j2000(self) -> tuple[float, float]:
        """(RA hours, Dec degrees), J2000, where the scope points now."""
        altitude, azimuth = self.sky_altaz_deg()
        return observed_to_j2000(altitude, azimuth, self._now(), self.site)

    def offsets_deg(self) -> tuple[float, float]:
        """(Alt, Az) from the scope to the current object; +Alt up, +Az counter-clockwise.

        Zero without a current object, so a GOTO then ends where it starts.
        """
        target = self.current_object
        if target is None:
            return 0.0, 0.0
        target_alt, target_az = j2000_to_observed(
            target.ra_hours, target.dec_degrees, self._now(), self.site
        )
        altitude, azimuth = self.sky_altaz_deg()
        return target_alt - altitude, -wrap_signed_degrees(target_az - azimuth)

    def rates_deg_per_min(self) -> tuple[float, float]:
        """(Alt, Az) apparent motion of the sky at the scope's position, degrees per minute."""
        now = self._now()
        altitude, azimuth = self.sky_altaz_deg()
        ra_hours, dec_degrees = observed_to_j2000(altitude, azimuth, now, self.site)
        later = now + timedelta(seconds=RATE_STEP_S)
        later_alt, later_az = j2000_to_observed(ra_hours, dec_degrees, later, self.site)
        scale = 60.0 / RATE_STEP_S
        return (later_alt - altitude) * scale, -wrap_signed_degrees(later_az - azimuth) * scale

    # --- commands -----------------------------------------------------------------------------

    def load(self, command: LoadObject) -> None:
        """``L99`` makes an object current; ``L00``-``L58`` store one (persisted at once)."""
        item = StoredObject(command.ra_hours, command.dec_degrees)
        if command.slot == TEMPORARY_SLOT:
            self.current_object = item
        else:
            self.store.store(command.slot, item)

    def realign(self) -> None:
        """``N``: from now on the encoders' present reading means the current object."""
        target = self.current_object
        if target is None:
            logger.info("N ignored: no current object")
            return
        target_alt, target_az = j2000_to_observed(
            target.ra_hours, target.dec_degrees, self._now(), self.site
        )
        altitude, azimuth = self._encoders()
        self.alignment = Alignment(target_alt - altitude, wrap_signed_degrees(target_az - azimuth))
        self.aligned = True

    def respond(self, event: object) -> bytes:
        """The reply bytes for one event of :class:`CommanderServer` (empty for none)."""
        match event:
            case ReadPosition():
                return PositionReply(*_clamped_position(self.position_j2000())).encode()
            case LoadObject():
                self.load(event)
                return Acknowledge().encode()
            case Realign():
                self.realign()
                return b""
            case ReadOffsets():
                return OffsetsReply(*self.offsets_deg()).encode()
            case ReadRates():
                return RatesReply(*self.rates_deg_per_min()).encode()
            case ErrorEvent():
                logger.info("Sky Commander ignores %s", event.describe())
                return b""
        raise TypeError(f"not a Sky Commander event: {event!r}")

    async def serve(self, port: DevicePort) -> None:
        """Answer commands on ``port`` until its link closes."""
        codec = CommanderServer()
        try:
            while True:
                try:
                    async with asyncio.timeout(LINE_TIMEOUT_S if codec.buffered else None):
                        codec.receive_data(await port.read())
                except TimeoutError:
                    dropped = codec.discard_partial()
                    if dropped is not None:
                        logger.info("Sky Commander: %s", dropped.describe())
                    continue
                while (event := codec.next_event()) is not NEED_DATA:
                    if not await port.reply(command_key(event), self.respond(event)):
                        return
        except LinkClosedError:
            return


def command_key(event: object) -> str:
    """The fault-injection key of a received command: its first byte, ``CR`` for a carriage
    return (so it can be written on a command line)."""
    if isinstance(event, ErrorEvent):
        first = event.data[:1]
    elif isinstance(event, Command):
        first = event.encode()[:1]
    else:
        return "?"
    return "CR" if first == b"\r" else first.decode("latin-1")


def _clamped_position(position: tuple[float, float]) -> tuple[float, float]:
    ra_hours, dec_degrees = position
    return ra_hours % 24.0, max(-90.0, min(90.0, dec_degrees))
