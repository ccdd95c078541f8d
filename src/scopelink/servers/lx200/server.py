"""The LX200 server: a handset on TCP (port 4030, as SkyFi and SkySafari use) or a pty.

Each link gets its own :class:`~scopelink.servers.lx200.device.LX200Session` and is answered in
order, one command at a time; while any link is served the mount's state cache is kept fresh
(``mount.watching()``), so reads answer at once. An incomplete command older than
:data:`PARTIAL_COMMAND_TIMEOUT_S` is dropped, so a client that gave up half-way does not poison
the next command.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Self

from scopelink.links import Link
from scopelink.mount import Mount
from scopelink.protocol.lx200 import (
    NEED_DATA,
    SKYFI_PORT,
    LX200ServerConnection,
    StrayBytes,
    UnknownCommand,
)
from scopelink.servers.access import AccessControl, AccessPolicy, current_client
from scopelink.servers.hosting import HostedDevice, WireSpeed
from scopelink.servers.lx200.config import LX200Config
from scopelink.servers.lx200.device import LX200Handset
from scopelink.servers.lx200.skyfi import SkyFiResponder

__all__ = ["DEFAULT_PORT", "PARTIAL_COMMAND_TIMEOUT_S", "LX200Server"]

logger = logging.getLogger(__name__)

DEFAULT_PORT = 4030
"""SkyFi's TCP port, where SkySafari connects after auto-detection."""

PARTIAL_COMMAND_TIMEOUT_S = 2.0


class LX200Server(HostedDevice):
    """An LX200 handset in front of ``mount`` (connected on entry if it is not yet)::

        async with LX200Server(mount) as server:
            await server.on_tcp()            # 127.0.0.1:4030
            path = await server.on_pty()     # and/or a serial-like device
            await server.on_skyfi()          # SkySafari's auto-detect on udp 127.0.0.1:4031

    ``wire`` paces replies like a serial line (None, the default, sends at once). ``access``
    limits who connects over TCP and how fast (commands beyond the rate wait), and makes the
    handset read-only; SkyFi ignores senders it does not admit.
    """

    def __init__(
        self,
        mount: Mount,
        config: LX200Config | None = None,
        *,
        wire: WireSpeed | None = None,
        access: AccessPolicy | None = None,
    ) -> None:
        self.handset = LX200Handset(mount, config)
        self.skyfi: SkyFiResponder | None = None
        super().__init__(self.serve, wire=wire, access=AccessControl(access, "LX200"))
        self.handset.read_only = self.access.read_only

    @property
    def mount(self) -> Mount:
        return self.handset.mount

    async def __aenter__(self) -> Self:
        if not self.mount.state.connected:
            await self.mount.connect()
        return self

    async def on_tcp(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT) -> tuple[str, int]:
        """Listen on ``host:port`` (0 picks a free port); returns the bound address."""
        return await super().on_tcp(host, port)

    async def on_skyfi(
        self, host: str = "127.0.0.1", port: int = SKYFI_PORT, *, name: str | None = None
    ) -> SkyFiResponder:
        """Answer SkySafari's SkyFi discovery on UDP ``host:port`` (stopped with the server)."""
        self.skyfi = SkyFiResponder(host, port, name=name, admits=self.access.allows)
        await self.skyfi.start()
        return self.skyfi

    async def close(self) -> None:
        if self.skyfi is not None:
            await self.skyfi.close()
        await super().close()

    async def serve(self, link: Link) -> None:
        """Answer commands from ``link`` until it closes."""
        session = self.handset.session()
        connection = LX200ServerConnection()
        client = current_client()
        # Dead-man: a slew this client started (:Ms#...) stops when its connection goes.
        async with self.mount.watching(), self.mount.motion_client(f"LX200 client {link.name}"):
            while True:
                data = await self._read(link, connection)
                if data is None:
                    dropped = connection.discard_partial()
                    logger.info("%s: incomplete command %r dropped", link.name, dropped)
                    continue
                connection.receive_data(data)
                while (event := connection.next_event()) is not NEED_DATA:
                    if isinstance(event, StrayBytes | UnknownCommand):
                        logger.info("%s: %s", link.name, event.describe())
                        continue
                    await client.throttle()
                    reply = await session.answer(event)
                    if reply:
                        await link.write(reply)

    async def _read(self, link: Link, connection: LX200ServerConnection) -> bytes | None:
        if not connection.pending:
            return await link.read()
        try:
            async with asyncio.timeout(PARTIAL_COMMAND_TIMEOUT_S):
                return await link.read()
        except TimeoutError:
            return None
