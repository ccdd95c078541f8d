"""One SynScan exchange from a test: send a command with our client codec, read its reply."""

from __future__ import annotations

import asyncio

from scopelink.links import Link
from scopelink.protocol.synscan import NEED_DATA, AnyCommand, AnyReply, SynScanClientConnection


async def ask(
    link: Link, client: SynScanClientConnection, command: AnyCommand, seconds: float = 5.0
) -> AnyReply:
    """Send ``command`` on ``link`` and return its reply (a failed test if another event comes,
    TimeoutError after ``seconds``)."""
    await link.write(client.send(command))
    async with asyncio.timeout(seconds):
        while (event := client.next_event()) is NEED_DATA:
            client.receive_data(await link.read())
    assert isinstance(event, AnyReply), event
    return event
