"""Stellarium's telescope-control server on TCP: any number of planetaria drive one mount.

Each connected client gets the mount's current position every ``interval_s`` seconds, read from
:attr:`Mount.state` (kept fresh by ``mount.watching()`` for as long as any client is connected),
and each goto it sends becomes :meth:`Mount.goto_equatorial`, whose horizon check refuses
anything below the configured horizon. The protocol has no error reply, so a refused goto is
logged and the position messages simply keep showing where the mount is. A position the mount
does not have (the link down, the reading older than ``stale_after_s``) is not sent: Stellarium
then keeps its reticle where the last message put it (and says nothing new), which is the only
honest form the protocol has; sending resumes with the next current reading.

Stellarium sends and expects J2000 unless its telescope is configured for JNow: ``frame``
must match that setting. JNow here means the apparent place of date (what the mount reports as
``ra_of_date_hours``).
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import logging
from collections.abc import Awaitable, Callable
from types import TracebackType
from typing import Self

from scopelink.astro import apparent_to_j2000
from scopelink.links import Link, LinkClosedError, TcpServer, serve_tcp
from scopelink.mount import Mount, MountError, MountState
from scopelink.protocol.stellarium import (
    NEED_DATA,
    BadLength,
    CurrentPosition,
    GotoMessage,
    SkippedMessage,
    StellariumServerConnection,
)
from scopelink.servers.access import AccessControl, AccessPolicy, ReadOnlyError, Refusal

__all__ = ["DEFAULT_PORT", "Equinox", "StellariumServer"]

logger = logging.getLogger(__name__)

DEFAULT_PORT = 10001
"""The port Stellarium's telescope plugin suggests for its first telescope."""

STATUS_OK = 0
STATUS_PROBLEM = -1
"""Sent while the mount reports a problem (the reading may be stale); Stellarium ignores it."""


class Equinox(enum.Enum):
    """The frame of the coordinates on the wire."""

    J2000 = "J2000"
    JNOW = "JNow"


class StellariumServer:
    """Serves Stellarium's binary protocol for ``mount`` on ``host:port`` (0 picks a free port).

    Use as ``async with StellariumServer(mount, port=0) as server:`` and read ``server.port``.
    The mount is connected on entry if it is not yet. ``access`` limits who connects and how
    many; gotos beyond its rate wait their turn, and a read-only policy refuses them (logged:
    the protocol has no refusal).
    """

    def __init__(
        self,
        mount: Mount,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        frame: Equinox = Equinox.J2000,
        interval_s: float = 0.5,
        access: AccessPolicy | None = None,
    ) -> None:
        if not 0.05 <= interval_s <= 10.0:
            raise ValueError(f"position interval {interval_s} s must lie in [0.05, 10]")
        self.mount = mount
        self.host = host
        self.port = port
        self.frame = frame
        self.interval_s = interval_s
        self.clients = 0
        """Clients connected now."""
        self.access = AccessControl(access, "Stellarium")
        self._server: TcpServer | None = None

    async def __aenter__(self) -> Self:
        await self.start()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await self.close()

    async def start(self) -> None:
        """Connect the mount if needed and start listening; :attr:`port` is then the bound port."""
        if not self.mount.state.connected:
            await self.mount.connect()
        self._server = await serve_tcp(self._serve, host=self.host, port=self.port)
        self.host, self.port = self._server.host, self._server.port
        logger.info("Stellarium server on %s:%d (%s)", self.host, self.port, self.frame.value)

    async def close(self) -> None:
        """Stop listening and drop every client."""
        if self._server is not None:
            await self._server.close()
            self._server = None

    # --- one client -----------------------------------------------------------------------------

    async def _serve(self, link: Link) -> None:
        async with self.access.session(getattr(link, "peer_host", None)) as client:
            if isinstance(client, Refusal):
                return  # the protocol has no refusal message: the connection just closes
            await self._serve_admitted(link, client.throttle)

    async def _serve_admitted(self, link: Link, throttle: Callable[[], Awaitable[None]]) -> None:
        self.clients += 1
        try:
            # The protocol starts no rate motion; the dead-man is there for uniformity.
            client = f"Stellarium client {link.name}"
            async with self.mount.watching(), self.mount.motion_client(client):
                sender = asyncio.create_task(self._send_positions(link), name=f"{link.name} out")
                try:
                    await self._read_gotos(link, throttle)
                finally:
                    sender.cancel()
                    with contextlib.suppress(asyncio.CancelledError, LinkClosedError):
                        await sender
        finally:
            self.clients -= 1

    async def _read_gotos(self, link: Link, throttle: Callable[[], Awaitable[None]]) -> None:
        connection = StellariumServerConnection()
        while True:
            connection.receive_data(await link.read())
            while (event := connection.next_event()) is not NEED_DATA:
                if isinstance(event, BadLength):
                    logger.warning("%s: %s; dropping the client", link.name, event.describe())
                    return
                if isinstance(event, SkippedMessage):
                    logger.info("%s: %s", link.name, event.describe())
                    continue
                await throttle()
                await self._goto(link, event)

    async def _goto(self, link: Link, goto: GotoMessage) -> None:
        ra, dec = goto.ra_hours, goto.dec_deg
        try:
            if self.access.read_only:
                raise ReadOnlyError("goto")
            if self.frame is Equinox.JNOW:
                if not -90.0 <= dec <= 90.0:
                    raise MountError(f"declination {dec:.4f}° lies beyond a pole")
                ra, dec = apparent_to_j2000(ra, dec, self.mount.now())
            await self.mount.goto_equatorial(ra, dec)
        except MountError as exc:
            logger.warning(
                "%s: goto RA %.5f h Dec %+.4f° (%s) refused: %s",
                link.name,
                goto.ra_hours,
                goto.dec_deg,
                self.frame.value,
                exc,
            )
            return
        logger.info(
            "%s: goto RA %.5f h Dec %+.4f° (%s)",
            link.name,
            goto.ra_hours,
            goto.dec_deg,
            self.frame.value,
        )

    async def _send_positions(self, link: Link) -> None:
        withheld = ""
        while True:
            try:
                state: MountState | None = self.mount.fresh_state()
            except MountError as error:
                state = None
                if not withheld:
                    logger.warning("%s: no position sent while: %s", link.name, error)
                withheld = str(error)
            else:
                if withheld:
                    logger.info("%s: current positions again", link.name)
                withheld = ""
            position = None if state is None else self.position_message(state)
            if position is not None:
                await link.write(position.encode())
            await asyncio.sleep(self.interval_s)

    def position_message(self, state: MountState) -> CurrentPosition | None:
        """The position message for ``state`` in this server's frame (None before a reading)."""
        if self.frame is Equinox.J2000:
            ra, dec = state.ra_j2000_hours, state.dec_j2000_deg
        else:
            ra, dec = state.ra_of_date_hours, state.dec_of_date_deg
        if ra is None or dec is None:
            return None
        status = STATUS_OK if state.connected and not state.problems else STATUS_PROBLEM
        time_us = round(state.read_at.timestamp() * 1_000_000)
        return CurrentPosition.from_degrees(ra, dec, time_us, status)
