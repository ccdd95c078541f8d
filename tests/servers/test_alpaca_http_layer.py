"""The Alpaca server's own HTTP/1.1 layer over raw sockets: keep-alive, pipelining, 100-continue,
chunked bodies, size limits and malformed requests — and garbage never takes the server down."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.servers.access import AccessControl
from scopelink.servers.alpaca.http import AlpacaHttpFront, HttpReply, HttpRequest
from scopelink.servers.hosts import HostAllowList
from scopelink.servers.http_guard import GuardedServer, HttpGuard
from tests.support.alpaca import API, read_reply, serve


async def raw(port: int) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
    return await asyncio.open_connection("127.0.0.1", port)


async def test_pipelined_requests_are_answered_in_order_on_one_connection(
    tmp_path: Path,
) -> None:
    async with serve(state_dir=tmp_path) as server:
        reader, writer = await raw(server.port)
        requests = b"".join(
            f"GET {API}/name?ClientTransactionID={n} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode()
            for n in range(1, 21)
        )
        writer.write(requests)
        async with asyncio.timeout(5):
            for n in range(1, 21):
                status, headers, body = await read_reply(reader)
                assert status == 200
                assert headers["content-type"].startswith("application/json")
                assert json.loads(body)["ClientTransactionID"] == n
        writer.close()


async def test_expect_continue_and_chunked_bodies_work_and_close_is_honoured(
    tmp_path: Path,
) -> None:
    async with serve(state_dir=tmp_path) as server:
        reader, writer = await raw(server.port)
        body = b"Connected=True&ClientTransactionID=7"
        writer.write(
            f"PUT {API}/connected HTTP/1.1\r\nHost: 127.0.0.1\r\nExpect: 100-continue\r\n"
            "Content-Type: application/x-www-form-urlencoded\r\n"
            f"Content-Length: {len(body)}\r\n\r\n".encode()
        )
        async with asyncio.timeout(5):
            assert await reader.readuntil(b"\r\n\r\n") == b"HTTP/1.1 100 Continue\r\n\r\n"
            writer.write(body)
            status, _, reply = await read_reply(reader)
        assert status == 200
        assert json.loads(reply)["ErrorNumber"] == 0
        chunked = b"Connected=False&ClientTransactionID=8"
        writer.write(
            f"PUT {API}/connected HTTP/1.1\r\nHost: 127.0.0.1\r\nTransfer-Encoding: chunked\r\n"
            "Connection: close\r\n\r\n".encode()
            + f"{len(chunked):x}\r\n".encode()
            + chunked
            + b"\r\n0\r\n\r\n"
        )
        async with asyncio.timeout(5):
            status, headers, reply = await read_reply(reader)
            assert status == 200
            assert headers["connection"] == "close"
            assert json.loads(reply)["ClientTransactionID"] == 8
            assert await reader.read() == b""  # the server closed the connection
        assert server.telescope.connected is False


async def test_bad_requests_get_400_or_413_and_the_connection_closes(tmp_path: Path) -> None:
    async with serve(state_dir=tmp_path) as server:
        for request, expected in (
            (b"THIS IS NOT HTTP\r\n\r\n", 400),
            (b"GET /a\x00b HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", 400),
            (
                f"PUT {API}/connected HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                "Content-Length: 10000000\r\n\r\n".encode(),
                413,
            ),
        ):
            reader, writer = await raw(server.port)
            writer.write(request)
            async with asyncio.timeout(5):
                status, _, _ = await read_reply(reader)
                assert status == expected, request
                assert await reader.read() == b""
            writer.close()
        # and the server still answers
        reader, writer = await raw(server.port)
        writer.write(f"GET {API}/name HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
        async with asyncio.timeout(5):
            status, _, _ = await read_reply(reader)
        assert status == 200
        writer.close()


def test_replies_carry_their_type_nosniff_and_extra_headers() -> None:
    reply = HttpReply(429, b"slow down", headers=(("Retry-After", "2"),))
    response = reply.response(close=True)
    assert response.status == 429
    assert response.headers["Content-Type"] == "text/plain; charset=utf-8"
    assert response.headers["X-Content-Type-Options"] == "nosniff"
    assert response.headers["Retry-After"] == "2"
    assert response.keep_alive is False


@given(st.binary(max_size=400), st.integers(min_value=1, max_value=50))
@settings(max_examples=150, deadline=None)
def test_any_bytes_in_any_chunks_give_replies_or_a_400_never_an_exception(
    data: bytes, chunk: int
) -> None:
    """Garbage over a real socket into the real HTTP front: every byte written back is an HTTP
    reply, and the server still answers afterwards."""

    async def handle(request: HttpRequest) -> HttpReply:
        return HttpReply.text(200, request.path)

    async def feed() -> bytes:
        front = AlpacaHttpFront(handle, AccessControl(), HostAllowList("127.0.0.1"))
        loop = asyncio.get_running_loop()
        listener = await loop.create_server(
            GuardedServer(front, guard=HttpGuard(AccessControl()), access_log=None),
            "127.0.0.1",
            0,
        )
        port = listener.sockets[0].getsockname()[1]
        reader, writer = await raw(port)
        for start in range(0, len(data), chunk):
            writer.write(data[start : start + chunk])
            await writer.drain()
        writer.write_eof()
        async with asyncio.timeout(5):
            written = await reader.read()
        writer.close()
        reader, writer = await raw(port)
        writer.write(b"GET /ok HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")
        async with asyncio.timeout(5):
            status, _, _ = await read_reply(reader)
        assert status == 200
        writer.close()
        listener.close()
        return written

    written = asyncio.run(feed())
    assert written == b"" or written[:9] in (b"HTTP/1.1 ", b"HTTP/1.0 ")
