"""The SkyFi discovery responder: lets SkySafari's "Auto-Detect SkyFi" find the LX200 server.

SkySafari sends ``skyfi?`` (or ``skyfi:NAME?``) to UDP port 4031 and connects to TCP port 4030 at
the address in the answer. This responder binds 127.0.0.1 by default; bind ``0.0.0.0`` to be
found on the LAN. It answers with the address the asking host reaches us at (the bound one, or,
when bound to every interface, the local address the kernel would route the answer from).
"""

from __future__ import annotations

import asyncio
import logging
import socket
from collections.abc import Callable
from types import TracebackType
from typing import Self, cast

from scopelink.protocol.lx200 import SKYFI_PORT, parse_skyfi_query, skyfi_reply

__all__ = ["SkyFiResponder"]

logger = logging.getLogger(__name__)


class SkyFiResponder:
    """Answers SkyFi discovery datagrams on ``host:port`` (port 0 picks a free one).

    ``name`` is the SkyFi name to answer to; None answers every query. ``admits`` says which
    sender addresses get an answer (the server's allow-list); the others are ignored.
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = SKYFI_PORT,
        *,
        name: str | None = None,
        admits: Callable[[str], bool] | None = None,
    ) -> None:
        self.admits = admits
        self.host = host
        self.port = port
        self.name = name
        self.answered = 0
        self._transport: asyncio.DatagramTransport | None = None

    async def start(self) -> None:
        loop = asyncio.get_running_loop()
        transport, _ = await loop.create_datagram_endpoint(
            lambda: _Protocol(self), local_addr=(self.host, self.port), family=socket.AF_INET
        )
        self._transport = transport
        self.host, self.port = transport.get_extra_info("sockname")[:2]
        logger.info("SkyFi discovery on udp %s:%d", self.host, self.port)

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()
            self._transport = None

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

    def reply_to(self, datagram: bytes, sender: tuple[str, int]) -> bytes | None:
        if self.admits is not None and not self.admits(sender[0]):
            logger.info("SkyFi: ignored a datagram from %s (not in the allow-list)", sender[0])
            return None
        query = parse_skyfi_query(datagram)
        if query is None:
            logger.info("SkyFi: ignored %d-byte datagram from %s", len(datagram), sender[0])
            return None
        if not query.matches(self.name):
            logger.info("SkyFi: %s asked for %r, we are %r", sender[0], query.name, self.name)
            return None
        self.answered += 1
        return skyfi_reply(query, self._address_towards(sender[0]))

    def _address_towards(self, peer: str) -> str:
        if self.host not in ("0.0.0.0", ""):
            return self.host
        # Connecting a UDP socket sends nothing; it only asks the kernel for the route.
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.connect((peer, SKYFI_PORT))
            address: str = probe.getsockname()[0]
            return address


class _Protocol(asyncio.DatagramProtocol):
    def __init__(self, responder: SkyFiResponder) -> None:
        self._responder = responder
        self._transport: asyncio.DatagramTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self._transport = cast("asyncio.DatagramTransport", transport)

    def datagram_received(self, data: bytes, addr: tuple[str | int, int]) -> None:
        sender = (str(addr[0]), int(addr[1]))
        reply = self._responder.reply_to(data, sender)
        if reply is not None and self._transport is not None:
            self._transport.sendto(reply, sender)
