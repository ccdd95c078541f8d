"""Alpaca management API, the persistent UniqueID, the setup pages and UDP discovery."""

from __future__ import annotations

import asyncio
import json
import socket
import time
import uuid
from pathlib import Path

import aiohttp
import pytest
from alpaca import management
from alpaca.telescope import Telescope

from scopelink.servers.alpaca import DISCOVERY_MESSAGE, AlpacaServer, TelescopeConfig
from scopelink.servers.alpaca.identity import UNIQUE_ID_FILE, load_or_create_unique_id
from tests.support.alpaca import blocking, serve, sim_mount


async def test_management_api_through_alpyca(tmp_path: Path) -> None:
    async with serve(state_dir=tmp_path) as server:
        address = f"127.0.0.1:{server.port}"
        assert await blocking(lambda: management.apiversions(address)) == [1]
        description = await blocking(lambda: management.description(address))
        assert description["ServerName"] == "scopelink"
        devices = await blocking(lambda: management.configureddevices(address))
        assert devices == [
            {
                "DeviceName": "scopelink telescope",
                "DeviceType": "Telescope",
                "DeviceNumber": 0,
                "UniqueID": server.unique_id,
            }
        ]
        assert uuid.UUID(server.unique_id).version == 4


async def test_unique_id_is_made_once_and_kept_across_restarts(tmp_path: Path) -> None:
    async with serve(state_dir=tmp_path) as first:
        unique_id = first.unique_id
    async with serve(state_dir=tmp_path) as second:
        assert second.unique_id == unique_id
    async with serve(state_dir=tmp_path / "elsewhere") as other:
        assert other.unique_id != unique_id
    stored = json.loads((tmp_path / UNIQUE_ID_FILE).read_text())
    assert stored == {"UniqueID": unique_id}
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]  # noqa: ASYNC240
    assert leftovers == []  # no temporary file left behind


def test_a_damaged_unique_id_file_is_reported_and_kept(tmp_path: Path) -> None:
    path = tmp_path / UNIQUE_ID_FILE
    path.write_text("{not json")
    with pytest.raises(ValueError, match="fix or delete it"):
        load_or_create_unique_id(tmp_path)
    assert path.read_text() == "{not json"


async def test_a_damaged_unique_id_file_stops_the_server_from_starting(tmp_path: Path) -> None:
    (tmp_path / UNIQUE_ID_FILE).write_text('{"UniqueID": "not-a-uuid"}')
    server = AlpacaServer(sim_mount(), port=0, discovery_port=None, state_dir=tmp_path)
    with pytest.raises(ValueError, match="UniqueID"):
        async with server:
            pass


async def test_setup_pages_show_the_site_and_escape_everything(tmp_path: Path) -> None:
    config = TelescopeConfig(name="<script>alert('x')</script> & co")
    async with (
        serve(state_dir=tmp_path, config=config) as server,
        aiohttp.ClientSession(base_url=server.url) as session,
    ):
        for path in ("/setup", "/setup/v1/telescope/0/setup"):
            async with session.get(path) as response:
                assert response.status == 200
                assert response.content_type == "text/html"
                page = await response.text()
            assert "<script>" not in page
            assert "&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt; &amp; co" in page
            assert "50.000000°" in page  # the site's latitude
            assert "Horizon" in page
            assert server.unique_id in page


async def test_closing_does_not_wait_for_idle_keep_alive_clients(tmp_path: Path) -> None:
    server = AlpacaServer(sim_mount(), port=0, discovery_port=None, state_dir=tmp_path)
    await server.start()
    telescope = Telescope(f"127.0.0.1:{server.port}", 0)  # keeps its connection open
    assert await blocking(lambda: telescope.Name) == "scopelink telescope"
    started = time.monotonic()
    await server.close()
    assert time.monotonic() - started < 0.9  # waiting for the client would take the 1 s grace


class _Receiver(asyncio.DatagramProtocol):
    def __init__(self) -> None:
        self.replies: asyncio.Queue[bytes] = asyncio.Queue()

    def datagram_received(self, data: bytes, addr: tuple[str | int, ...]) -> None:
        self.replies.put_nowait(data)


async def test_discovery_answers_with_the_alpaca_port_on_loopback(tmp_path: Path) -> None:
    async with serve(state_dir=tmp_path, discovery=True) as server:
        assert server.discovery_port not in (None, 0)
        loop = asyncio.get_running_loop()
        transport, receiver = await loop.create_datagram_endpoint(
            _Receiver, local_addr=("127.0.0.1", 0), family=socket.AF_INET
        )
        try:
            target = ("127.0.0.1", server.discovery_port)
            transport.sendto(b"hello", target)  # not a discovery request: ignored
            transport.sendto(DISCOVERY_MESSAGE, target)
            reply = await asyncio.wait_for(receiver.replies.get(), 5.0)
            assert json.loads(reply) == {"AlpacaPort": server.port}
            await asyncio.sleep(0.2)
            assert receiver.replies.empty()
        finally:
            transport.close()
