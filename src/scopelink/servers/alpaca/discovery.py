"""Alpaca discovery: answer the UDP datagram ``alpacadiscovery1`` with the HTTP port.

Discovery clients broadcast the 16-byte text to port 32227; every Alpaca server replies, to
the sender only, with ``{"AlpacaPort": N}``. Anything else arriving on the port is ignored.
"""

from __future__ import annotations

import asyncio
import json
import logging
import socket
from collections.abc import Callable
from typing import cast

__all__ = ["DISCOVERY_MESSAGE", "DISCOVERY_PORT", "DiscoveryResponder", "start_discovery"]

logger = logging.getLogger(__name__)

DISCOVERY_PORT = 32227
DISCOVERY_MESSAGE = b"alpacadiscovery1"


class DiscoveryResponder(asyncio.DatagramProtocol):
    """Replies to each discovery datagram with the Alpaca HTTP port (to senders ``admits``
    accepts, when given: the others are ignored)."""

    def __init__(self, alpaca_port: int, admits: Callable[[str], bool] | None = None) -> None:
        self._admits = admits
        self._reply = json.dumps({"AlpacaPort": alpaca_port}).encode("ascii")
        self._transport: asyncio.DatagramTransport | None = None
        self.answered = 0

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self._transport = cast(asyncio.DatagramTransport, transport)

    def datagram_received(self, data: bytes, addr: tuple[str | int, ...]) -> None:
        # The spec's clients send exactly the message; version 1 ignores anything after it.
        if not data.startswith(DISCOVERY_MESSAGE) or self._transport is None:
            return
        if self._admits is not None and not self._admits(str(addr[0])):
            logger.info("Alpaca discovery: ignored %s (not in the allow-list)", addr[0])
            return
        self._transport.sendto(self._reply, addr)
        self.answered += 1

    def error_received(self, exc: Exception) -> None:
        logger.info("Alpaca discovery socket: %s", exc)


async def start_discovery(
    host: str, port: int, alpaca_port: int, *, admits: Callable[[str], bool] | None = None
) -> tuple[asyncio.DatagramTransport, DiscoveryResponder]:
    """Listen for discovery datagrams on ``host:port`` (0 picks a free port)."""
    loop = asyncio.get_running_loop()
    # Several Alpaca servers on one machine (ASCOM Remote, other drivers) share port 32227: each
    # answers the broadcasts it receives. Windows has no SO_REUSEPORT.
    transport, responder = await loop.create_datagram_endpoint(
        lambda: DiscoveryResponder(alpaca_port, admits),
        local_addr=(host, port),
        reuse_port=hasattr(socket, "SO_REUSEPORT"),
    )
    return transport, responder
