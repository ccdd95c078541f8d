"""open_link: every supported spelling opens the right link; bad ones get clear errors."""

import asyncio
import socket

import pytest

from scopelink.links import (
    Link,
    LinkOpenError,
    LinkSpecError,
    PacedLink,
    SerialLink,
    TcpClientLink,
    open_link,
    serve_tcp,
)


async def shout_back(link: Link) -> None:
    while True:
        await link.write((await link.read()).upper())


async def round_trip(link: Link) -> bytes:
    async with link:
        await link.write(b"ping")
        return await asyncio.wait_for(link.read_exactly(4), 2.0)


async def test_tcp_and_socket_urls_reach_our_server() -> None:
    async with await serve_tcp(shout_back) as server:
        tcp = await open_link(f"tcp://127.0.0.1:{server.port}")
        assert isinstance(tcp, TcpClientLink)
        assert await round_trip(tcp) == b"PING"
        bridged = await open_link(f" socket://127.0.0.1:{server.port} ")
        assert isinstance(bridged, SerialLink)
        assert await round_trip(bridged) == b"PING"


async def test_loop_url_opens_a_serial_loopback() -> None:
    link = await open_link("loop://", 9600, stopbits=2)
    assert isinstance(link, SerialLink)
    assert await round_trip(link) == b"ping"


async def test_pace_wraps_only_links_without_a_uart() -> None:
    paced_loop = await open_link("loop://", 9600, stopbits=2, pace=True)
    assert isinstance(paced_loop, PacedLink)
    assert paced_loop.bits_per_byte == 11
    await paced_loop.close()
    async with await serve_tcp(shout_back) as server:
        paced_tcp = await open_link(f"tcp://127.0.0.1:{server.port}", pace=True)
        assert isinstance(paced_tcp, PacedLink)
        assert paced_tcp.bits_per_byte == 10
        assert await round_trip(paced_tcp) == b"PING"


@pytest.mark.parametrize("spec", ["/dev/ttyNOPE9", "COM3"])
async def test_device_names_are_opened_as_serial_ports(spec: str) -> None:
    with pytest.raises(LinkOpenError, match=f"cannot open {spec}: no such device"):
        await open_link(spec)


async def test_a_refused_tcp_url_is_an_open_error() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(LinkOpenError, match="connection refused"):
        await open_link(f"tcp://127.0.0.1:{port}")


@pytest.mark.parametrize(
    ("spec", "complaint"),
    [
        ("", "empty link spec"),
        ("   ", "empty link spec"),
        ("tcp://127.0.0.1", "needs a host and a port"),
        ("tcp://127.0.0.1:http", "needs a host and a port"),
        ("tcp://:11880", "needs a host and a port"),
        ("socket://127.0.0.1", r"like socket://HOST:PORT"),
        ("rfc2217://:2217", r"like rfc2217://HOST:PORT"),
        ("http://127.0.0.1:80", "unknown link scheme 'http'"),
        ("127.0.0.1:11880", "did you mean tcp://127.0.0.1:11880"),
    ],
)
async def test_bad_specs_are_refused_clearly(spec: str, complaint: str) -> None:
    with pytest.raises(LinkSpecError, match=complaint):
        await open_link(spec)
