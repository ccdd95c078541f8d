"""Helpers for the access-policy tests: raw HTTP over asyncio streams, and the policies used.

The allow-list cannot be tested from another address (tests talk to 127.0.0.1 only), so the
refusing policy turns off the loopback exemption: 127.0.0.1 is then outside the allowed
network like any stranger.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
from dataclasses import dataclass

from scopelink.servers.access import AccessPolicy, parse_network

ELSEWHERE_ONLY = AccessPolicy(allow=(parse_network("10.9.8.0/24"),), loopback_always_allowed=False)
"""Admits only 10.9.8.0/24: every test client (127.0.0.1) is a stranger."""
READ_ONLY = AccessPolicy(read_only=True)


@dataclass(frozen=True)
class HttpAnswer:
    status: int
    headers: dict[str, str]
    body: bytes

    def json(self) -> dict[str, object]:
        value: dict[str, object] = json.loads(self.body)
        return value


async def read_answer(reader: asyncio.StreamReader, timeout_s: float = 5.0) -> HttpAnswer:
    """One HTTP/1.1 response (Content-Length framed)."""
    async with asyncio.timeout(timeout_s):
        head = await reader.readuntil(b"\r\n\r\n")
        lines = head.decode("latin-1").split("\r\n")
        status = int(lines[0].split(" ", 2)[1])
        headers = {}
        for line in lines[1:]:
            if ":" in line:
                name, value = line.split(":", 1)
                headers[name.strip().lower()] = value.strip()
        body = await reader.readexactly(int(headers.get("content-length", "0")))
    return HttpAnswer(status, headers, body)


class HttpClient:
    """A keep-alive HTTP/1.1 connection to 127.0.0.1:``port``."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader = reader
        self.writer = writer

    @classmethod
    async def connect(cls, port: int) -> HttpClient:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        return cls(reader, writer)

    async def request(self, method: str, path: str, form: str = "") -> HttpAnswer:
        body = form.encode()
        head = f"{method} {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        if method != "GET":
            head += "Content-Type: application/x-www-form-urlencoded\r\n"
            head += f"Content-Length: {len(body)}\r\n"
        self.writer.write(head.encode() + b"\r\n" + body)
        await self.writer.drain()
        return await read_answer(self.reader)

    async def closed_by_server(self, timeout_s: float = 5.0) -> bool:
        async with asyncio.timeout(timeout_s):
            return await self.reader.read(1) == b""

    async def close(self) -> None:
        self.writer.close()
        with contextlib.suppress(OSError):
            await self.writer.wait_closed()


async def closed_without_a_byte(port: int, probe: bytes, timeout_s: float = 5.0) -> bool:
    """Connect to 127.0.0.1:``port``, send ``probe``: True when the server hangs up without
    answering (how line protocols refuse a connection)."""
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        try:
            writer.write(probe)
            await writer.drain()
        except ConnectionError:
            return True
        async with asyncio.timeout(timeout_s):
            try:
                return await reader.read(100) == b""
            except ConnectionError:
                return True
    finally:
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()
