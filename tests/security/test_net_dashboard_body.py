"""Found by the dashboard-http fuzz target (issue #12, part 7): a JSON command whose body arrives
in two TCP segments (a phone on Wi-Fi, a slow link) was read only up to the first one and
answered 400 "not valid JSON"."""

from __future__ import annotations

import asyncio

from scopelink.web import Dashboard
from tests.support.alpaca import sim_mount


async def test_a_command_body_split_across_segments_is_read_whole() -> None:
    mount = sim_mount()
    await mount.connect()
    try:
        async with Dashboard(mount, port=0, trace=False) as served:
            body = b'{"mode": "sidereal"}'
            reader, writer = await asyncio.open_connection("127.0.0.1", served.port)
            writer.write(
                f"POST /api/tracking HTTP/1.1\r\nHost: 127.0.0.1:{served.port}\r\n"
                f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n"
                "Connection: close\r\n\r\n".encode()
                + body[:7]
            )
            await writer.drain()
            await asyncio.sleep(0.2)  # the rest of the body comes later
            writer.write(body[7:])
            async with asyncio.timeout(5):
                status_line = await reader.readline()
                answer = await reader.read()
            writer.close()
            assert status_line.startswith(b"HTTP/1.1 200"), answer
    finally:
        await mount.disconnect()
