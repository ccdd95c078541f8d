"""Pass bytes both ways between two links, telling an observer about every transfer.

``scopelink record`` puts this between a client's pty (or TCP connection) and the device, so
any program's session is kept byte for byte with its time.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from scopelink.links.base import Link, LinkClosedError

__all__ = ["Observer", "relay"]

Observer = Callable[[bool, bytes], None]
"""Called with ``(from_client, data)`` as each read returns, before the bytes are passed on."""


async def relay(client: Link, device: Link, observe: Observer) -> None:
    """Relay until either link ends (then return; ``device.closed`` says whether it was the
    device) or the caller cancels. Closes neither link."""

    async def pump(source: Link, sink: Link, from_client: bool) -> None:
        while True:
            data = await source.read()
            observe(from_client, data)
            await sink.write(data)

    tasks = [
        asyncio.create_task(pump(client, device, True)),
        asyncio.create_task(pump(device, client, False)),
    ]
    try:
        await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in tasks:
            task.cancel()
        results = await asyncio.gather(*tasks, return_exceptions=True)
    for result in results:
        if isinstance(result, BaseException) and not isinstance(
            result, LinkClosedError | asyncio.CancelledError
        ):
            raise result
