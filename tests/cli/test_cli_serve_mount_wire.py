"""The command line's requests to a running serve's dashboard (ServeMount) go straight to the
registered address: never through a proxy of the environment (``http_proxy``, which would get the
pairing token and every command), never on to where a redirect points."""

from __future__ import annotations

import asyncio
import os

import pytest

from scopelink.cli.serve_mount import ServeMount
from scopelink.cli.serve_registry import ServeEntry
from scopelink.mount import MountError
from scopelink.web import Dashboard
from tests.support.web import sim_mount

TOKEN = "pairing-token-that-must-stay-home"


async def _recorder(heard: list[bytes], answer: bytes) -> asyncio.Server:
    """A listener on 127.0.0.1 that keeps what it hears and answers ``answer``."""

    async def serve(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        head = await reader.readuntil(b"\r\n\r\n")
        heard.append(head)
        writer.write(answer)
        await writer.drain()
        writer.close()

    return await asyncio.start_server(serve, "127.0.0.1", 0)


async def test_no_proxy_and_no_redirect_sees_the_token(monkeypatch: pytest.MonkeyPatch) -> None:
    proxied: list[bytes] = []
    proxy = await _recorder(proxied, b"HTTP/1.1 502 Bad Gateway\r\nContent-Length: 0\r\n\r\n")
    proxy_port = proxy.sockets[0].getsockname()[1]
    for name in ("http_proxy", "HTTP_PROXY", "all_proxy", "ALL_PROXY"):
        monkeypatch.setenv(name, f"http://127.0.0.1:{proxy_port}")
    monkeypatch.delenv("no_proxy", raising=False)
    monkeypatch.delenv("NO_PROXY", raising=False)
    assert os.environ["http_proxy"]
    mount = sim_mount()
    await mount.connect()
    try:
        async with (
            proxy,
            Dashboard(
                mount, port=0, pairing_token=TOKEN, pairing_exempts_loopback=False
            ) as dashboard,
        ):
            entry = ServeEntry(1, dashboard.url, {"pairing": TOKEN})
            served = await ServeMount.open(entry)
            await served.park()  # a command: it needs the token, and reaches the serve
            assert mount.state.parked
            assert proxied == []

            # A redirect (whoever answers on the registered port) is not followed.
            elsewhere: list[bytes] = []
            target = await _recorder(elsewhere, b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\n{}")
            target_port = target.sockets[0].getsockname()[1]
            moved = (
                f"HTTP/1.1 302 Found\r\nLocation: http://127.0.0.1:{target_port}/api/state\r\n"
                "Content-Length: 0\r\n\r\n"
            ).encode()
            redirecting = await _recorder([], moved)
            async with target, redirecting:
                port = redirecting.sockets[0].getsockname()[1]
                served.url = f"http://127.0.0.1:{port}"
                with pytest.raises(MountError):
                    await served.refresh()
            assert elsewhere == []
    finally:
        await mount.disconnect()
