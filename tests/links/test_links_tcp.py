"""TCP client and server links over real sockets on 127.0.0.1."""

import asyncio
import socket

import pytest

from scopelink.links import Link, LinkClosedError, LinkOpenError, TcpServer, open_tcp, serve_tcp
from scopelink.protocol.base import NEED_DATA


async def shout_back(link: Link) -> None:
    """Answer every chunk in upper case until the client goes away."""
    while True:
        await link.write((await link.read()).upper())


def unused_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


async def test_client_and_server_talk_both_ways() -> None:
    async with await serve_tcp(shout_back) as server:
        assert server.host == "127.0.0.1"
        assert server.port > 0
        async with await open_tcp("127.0.0.1", server.port) as client:
            assert client.name == f"tcp 127.0.0.1:{server.port}"
            await client.write(b"hello")
            assert await client.read_exactly(5) == b"HELLO"
            await client.write(b":j1\r")
            assert await client.read_exactly(4) == b":J1\r"


async def test_server_side_sees_client_close_as_link_closed() -> None:
    outcome: asyncio.Future[BaseException] = asyncio.get_running_loop().create_future()

    async def record_end(link: Link) -> None:
        try:
            await link.read()
        except LinkClosedError as exc:
            outcome.set_result(exc)
            raise

    async with await serve_tcp(record_end) as server:
        client = await open_tcp("127.0.0.1", server.port)
        await client.close()
        assert isinstance(await asyncio.wait_for(outcome, 2.0), LinkClosedError)


async def test_client_read_after_server_hangs_up_raises_link_closed() -> None:
    async def say_bye(link: Link) -> None:
        await link.write(b"bye")

    async with (
        await serve_tcp(say_bye) as server,
        await open_tcp("127.0.0.1", server.port) as client,
    ):
        assert await client.read_exactly(3) == b"bye"
        with pytest.raises(LinkClosedError, match="closed by the peer"):
            await asyncio.wait_for(client.read(), 2.0)
        assert client.closed


async def test_server_close_ends_connections_and_stops_listening() -> None:
    handler_ended: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    async def wait_forever_for_input(link: Link) -> None:
        try:
            await link.read()
        except LinkClosedError:
            handler_ended.set_result("link closed")

    server = await serve_tcp(wait_forever_for_input)
    client = await open_tcp("127.0.0.1", server.port)
    await asyncio.sleep(0.05)  # let the server accept
    await asyncio.wait_for(server.close(), 2.0)
    assert handler_ended.result() == "link closed"
    with pytest.raises(LinkClosedError):
        await asyncio.wait_for(client.read(), 2.0)
    await client.close()
    with pytest.raises(LinkOpenError, match="connection refused"):
        await open_tcp("127.0.0.1", server.port)


async def test_server_close_cancels_a_handler_that_ignores_its_link() -> None:
    cancelled = asyncio.Event()

    async def stubborn(_link: Link) -> None:
        try:
            await asyncio.sleep(60)
        except asyncio.CancelledError:
            cancelled.set()
            raise

    server: TcpServer = await serve_tcp(stubborn)
    client = await open_tcp("127.0.0.1", server.port)
    await asyncio.sleep(0.05)
    await asyncio.wait_for(server.close(), 3.0)
    assert cancelled.is_set()
    await client.close()


async def test_a_failing_handler_is_logged_and_the_server_keeps_serving(
    caplog: pytest.LogCaptureFixture,
) -> None:
    calls = 0

    async def fail_first_time(link: Link) -> None:
        nonlocal calls
        calls += 1
        if calls == 1:
            raise RuntimeError("handler bug")
        await shout_back(link)

    async with await serve_tcp(fail_first_time) as server:
        first = await open_tcp("127.0.0.1", server.port)
        with pytest.raises(LinkClosedError):
            await asyncio.wait_for(first.read(), 2.0)
        async with await open_tcp("127.0.0.1", server.port) as second:
            await second.write(b"ok")
            assert await second.read_exactly(2) == b"OK"
    assert "connection handler failed" in caplog.text
    assert "handler bug" in caplog.text


async def test_connecting_to_a_closed_port_names_it() -> None:
    port = unused_port()
    with pytest.raises(LinkOpenError, match=f"tcp 127.0.0.1:{port}: connection refused"):
        await open_tcp("127.0.0.1", port)


async def test_listening_on_a_busy_port_says_so() -> None:
    async with await serve_tcp(shout_back) as server:
        with pytest.raises(LinkOpenError, match=f"127.0.0.1:{server.port}"):
            await serve_tcp(shout_back, port=server.port)


async def test_client_write_and_read_event_sends_at_once_then_waits_under_back_pressure() -> None:
    """``write_and_read_event`` hands a command over without a coroutine; when the peer stops
    reading and the kernel's buffers fill, it sends nothing and says so (None), ``write`` waits
    for the drain, and every byte arrives in order once the peer reads again (nothing lost,
    nothing doubled)."""
    reading = asyncio.Event()
    received = bytearray()
    arrived = asyncio.Event()

    async def slow_reader(link: Link) -> None:
        await reading.wait()
        while True:
            received.extend(await link.read())
            arrived.set()

    def write_now(client: Link, data: bytes) -> bool:
        """Hand ``data`` over if the link can at once; the read it starts is given up."""
        read: asyncio.Future[None] | None = client.write_and_read_event(data, lambda _: NEED_DATA)
        if read is None:
            return False
        read.cancel()
        return True

    async with await serve_tcp(slow_reader) as server:
        async with await open_tcp("127.0.0.1", server.port) as client:
            assert write_now(client, b"e")
            chunk = bytes(range(256)) * 256
            sent = 1
            while write_now(client, chunk):  # the transport takes it until its buffer is high
                sent += len(chunk)
                assert sent < 200_000_000, "write_and_read_event never reported back-pressure"
            pending = asyncio.create_task(client.write(chunk))
            await asyncio.sleep(0.05)
            assert not pending.done(), "write did not wait for the buffer to drain"
            reading.set()
            await asyncio.wait_for(pending, 10.0)
            sent += len(chunk)
            assert client.bytes_written == sent
            async with asyncio.timeout(10.0):
                while len(received) < sent:
                    arrived.clear()
                    await arrived.wait()
            assert received[:1] == b"e"
            assert bytes(received[1:]) == chunk * ((sent - 1) // len(chunk))
        assert not write_now(client, b"e")  # closed: nothing sent, the caller's write raises
