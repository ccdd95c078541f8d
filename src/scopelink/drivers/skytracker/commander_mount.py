"""``SkyCommanderMount``: a Sky Commander alone on its own port (push-to, no Sky Tracker).

The Sky Commander is a pair of digital setting circles: it reads the encoders of a mount that is
pushed by hand, and knows where it points once its user has aligned it. Alone it cannot move
anything, so this Mount reads (``\\r``: J2000 RA/Dec), syncs (``L99`` + ``N``: realign on an
object) and stores objects in the box's memory (``L00``-``L58``); gotos, motion and tracking are
"not supported". It is the ``skycommander:PORT`` device (``scopelink.drivers.open``), so
``scopelink serve`` shows a push-to scope in the dashboard, Stellarium and Alpaca clients.
See ``docs/drivers-skytracker.md``, "Sky Commander memory and push-to".
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from datetime import datetime
from typing import Any, Self

from scopelink.astro import Site
from scopelink.drivers.common import LinkFactory, Pointing, link_factory
from scopelink.links import Link, LinkError
from scopelink.mount import (
    AlignmentMode,
    Capabilities,
    DeviceError,
    Identity,
    Limits,
    Mount,
    MountState,
    NotConnectedError,
    TrackingMode,
    utc_now,
)
from scopelink.mount.scheduling import Priority, WireScheduler
from scopelink.protocol.skytracker import (
    NEED_DATA,
    Acknowledge,
    BadReply,
    CommanderClient,
    CommanderCommand,
    LoadObject,
    PositionReply,
    ReadPosition,
    Realign,
    Reply,
    StrayByte,
)

from .base import BAUDRATE
from .exchange import DEFAULT_TIMEOUT_S, RESYNC_QUIET_S, BadReplyError, ReplyTimeoutError
from .memory import stored_object
from .realign import realign_on

__all__ = ["SkyCommanderMount"]

logger = logging.getLogger(__name__)

_CAPABILITIES = Capabilities(alignment_mode=AlignmentMode.ALT_AZ, can_sync=True, can_set_site=True)
"""A Sky Commander alone: positions and syncs, the same whatever it answers (read per publish)."""


class SkyCommanderMount(Mount):
    """A Sky Commander on ``link`` (a serial port, ``tcp://HOST:PORT``, a pty path).

    One exchange at a time; a failed one (timeout, a reply that does not parse) is tried once
    more after draining the line. ``timeout_s`` bounds each reply (default 1 s, as the Sky
    Tracker driver's: the longest reply, 16 bytes, takes 17 ms).
    """

    poll_interval_s = 0.0

    def __init__(
        self,
        link: str | LinkFactory,
        *,
        site: Site,
        limits: Limits | None = None,
        clock: Callable[[], datetime] = utc_now,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        name: str | None = None,
    ) -> None:
        super().__init__(site=site, limits=limits, clock=clock)
        if not timeout_s > 0:
            raise ValueError(f"timeout {timeout_s} s must be positive")
        self._open, self.spec = link_factory(
            link,
            name=name,
            unnamed="Sky Commander link",
            baudrate=BAUDRATE,  # the Sky Commander's own port: 9600 8N1, as INDI opens it
            stopbits=1,
            pace=True,
        )
        self.timeout_s = timeout_s
        self.scheduler = WireScheduler()
        self._link: Link | None = None
        self._client = CommanderClient()
        self._position: Pointing | None = None
        self._problems: tuple[str, ...] = ()
        self._engaged = False
        """connect() succeeded and disconnect() was not called since: a lost link is reopened."""

    @classmethod
    async def open(cls, link: str | LinkFactory, **options: Any) -> Self:
        """Construct the driver for ``link`` and connect it; ``options`` are the constructor's."""
        mount = cls(link, **options)
        await mount.connect()
        return mount

    @property
    def capabilities(self) -> Capabilities:
        return _CAPABILITIES

    @property
    def identity(self) -> Identity:
        return Identity("skycommander", "Sky Commander", link=self.spec)

    @property
    def engaged(self) -> bool:
        return self._engaged

    def _line_bytes(self) -> tuple[int, int]:
        link = self._link
        return (link.bytes_written, link.bytes_read) if link is not None else (0, 0)

    # --- connection ---------------------------------------------------------------------------

    async def connect(self) -> None:
        """Open the link and read a position: a Sky Commander answers ``\\r`` with 16 bytes."""
        if self._link is not None and not self._link.closed:
            return
        await self._open_link()
        try:
            await self.refresh()
        except DeviceError as error:
            await self.disconnect()
            raise DeviceError(f"no Sky Commander answered on {self.spec}: {error}") from None
        self._engaged = True

    async def _open_link(self) -> None:
        try:
            self._link = await self._open()
        except (LinkError, OSError) as error:
            raise NotConnectedError(f"cannot open the Sky Commander's link: {error}") from error
        self._client = CommanderClient()

    async def disconnect(self) -> None:
        self._engaged = False
        link, self._link = self._link, None
        if link is not None:
            with contextlib.suppress(LinkError):
                await link.close()
        self._publish_now()

    # --- reads and commands -------------------------------------------------------------------

    async def refresh(self) -> MountState:
        reply = await self.ask(ReadPosition(), Priority.POLL)
        assert isinstance(reply, PositionReply)
        self._position = Pointing(reply.ra_hours, reply.dec_degrees, self.now(), self.site)
        return self._publish_now()

    async def store_object(self, slot: int, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """``Lnn``: store J2000 coordinates in slot ``slot`` (0-58) of the box's memory."""
        command = stored_object(slot, ra_j2000_hours, dec_j2000_deg)
        reply = await self.ask(command)
        if not isinstance(reply, Acknowledge):
            raise DeviceError(f"the Sky Commander did not acknowledge {command.describe()}")

    async def _sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """``L99`` then ``N`` (realign); the position read back tells that ``N`` took."""
        load = LoadObject.current(ra_j2000_hours, dec_j2000_deg)

        async def load_and_realign() -> Reply | None:
            reply = await self.ask(load)
            await self.ask(Realign())
            return reply

        async def read_back() -> tuple[float, float]:
            state = await self.refresh()
            assert state.ra_j2000_hours is not None
            assert state.dec_j2000_deg is not None
            return state.ra_j2000_hours, state.dec_j2000_deg

        await realign_on(ra_j2000_hours, dec_j2000_deg, load_and_realign, read_back)

    async def _set_site(self, site: Site) -> None:
        if self._position is not None:
            self._position = self._position.at_site(site)
            self._publish_now()

    async def ask(
        self, command: CommanderCommand, priority: Priority = Priority.COMMAND
    ) -> Reply | None:
        """One command and its reply, in one turn; a failed exchange is tried once more."""
        async with self.scheduler.turn(priority):
            link = self._link
            if self._engaged and (link is None or link.closed):
                logger.info("the Sky Commander's link %s closed: opening it again", self.spec)
                await self._open_link()
            try:
                return await self._exchange(command)
            except (ReplyTimeoutError, BadReplyError) as error:
                logger.info("Sky Commander exchange failed, trying once more: %s", error)
                await self._drain()
                return await self._exchange(command)

    async def _exchange(self, command: CommanderCommand) -> Reply | None:
        link = self._link
        if link is None or link.closed:
            raise NotConnectedError(f"the Sky Commander on {self.spec} is not connected")
        try:
            await link.write(self._client.send(command))
            if command.reply is None:
                return None
            async with asyncio.timeout(self.timeout_s):
                while True:
                    event = self._client.next_event()
                    if event is NEED_DATA:
                        self._client.receive_data(await link.read())
                    elif isinstance(event, StrayByte):
                        logger.info("Sky Commander: %s", event.describe())
                    elif isinstance(event, BadReply):
                        raise BadReplyError(f"Sky Commander on {self.spec}: {event.describe()}")
                    elif isinstance(event, Reply):
                        return event
        except TimeoutError:
            self._client.abandon_reply()
            raise ReplyTimeoutError(
                f"no reply from the Sky Commander on {self.spec} to {command.describe()!r} "
                f"within {self.timeout_s:g} s"
            ) from None
        except LinkError as error:
            self._publish_now()  # connected is false once the link has closed
            raise NotConnectedError(f"the link {self.spec} failed: {error}") from error

    async def _drain(self) -> None:
        """Drop input until the line has been quiet for ``RESYNC_QUIET_S``; a fresh codec."""
        link = self._link
        if link is not None:
            with contextlib.suppress(TimeoutError, LinkError):
                while True:
                    async with asyncio.timeout(RESYNC_QUIET_S):
                        await link.read()
        self._client = CommanderClient()

    def _publish_now(self) -> MountState:
        position = self._position
        link = self._link
        state = MountState(
            read_at=position.read_at if position else self.now(),
            connected=link is not None and not link.closed,
            ra_j2000_hours=position.ra_j2000_hours if position else None,
            dec_j2000_deg=position.dec_j2000_deg if position else None,
            ra_of_date_hours=position.ra_of_date_hours if position else None,
            dec_of_date_deg=position.dec_of_date_deg if position else None,
            alt_deg=position.alt_deg if position else None,
            az_deg=position.az_deg if position else None,
            tracking=TrackingMode.OFF,
            aligned=True,
            problems=self._problems,
            received_s=position.received_s if position else time.monotonic(),
        )
        self._publish(state)
        return state
