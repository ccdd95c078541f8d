"""Serial links through pyserial: socket:// against our TCP server, loop://, and open errors."""

import asyncio
import errno
import socket
import time

import pytest
import serial
from serial.urlhandler import protocol_loop, protocol_socket

from scopelink.links import (
    Link,
    LinkClosedError,
    LinkOpenError,
    LinkSpecError,
    open_pty,
    open_serial,
    serve_tcp,
)
from scopelink.links.serial import _open_error


async def shout_back(link: Link) -> None:
    while True:
        await link.write((await link.read()).upper())


async def test_socket_url_talks_to_our_tcp_server_both_ways() -> None:
    async with await serve_tcp(shout_back) as server:
        url = f"socket://127.0.0.1:{server.port}"
        async with await open_serial(url) as link:
            assert link.name == url
            await link.write(b":e1\r")
            assert await asyncio.wait_for(link.read_exactly(4), 2.0) == b":E1\r"


SLOW_PORT_S = 0.5
"""Opening and closing a port take this long here (a USB adapter can): on the event loop it
would stall everything else for as long."""


async def test_opening_and_closing_never_stall_the_event_loop(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    for port_class in (protocol_socket.Serial, protocol_loop.Serial):
        for method in ("open", "close"):
            original = getattr(port_class, method)

            def slow(
                self: serial.SerialBase, _original: object = original, _method: str = method
            ) -> None:
                # A closed port's close (io's finalizer calls it again) costs nothing.
                if _method == "open" or self.is_open:
                    time.sleep(SLOW_PORT_S)
                _original(self)  # type: ignore[operator]

            monkeypatch.setattr(port_class, method, slow)
    loop = asyncio.get_running_loop()
    longest_gap = 0.0

    async def tick() -> None:
        nonlocal longest_gap
        last = loop.time()
        while True:
            await asyncio.sleep(0.005)
            longest_gap = max(longest_gap, loop.time() - last)
            last = loop.time()

    async with await serve_tcp(shout_back) as server:
        ticker = asyncio.create_task(tick())
        for url in (f"socket://127.0.0.1:{server.port}", "loop://"):
            link = await open_serial(url)
            await link.write(b"x")
            await asyncio.wait_for(link.read(), 2.0)
            await link.close()
        ticker.cancel()
    assert longest_gap < SLOW_PORT_S * 0.8, longest_gap  # never the port's time (ticks: 5 ms)


async def test_socket_url_reports_the_server_hanging_up() -> None:
    async def hang_up(link: Link) -> None:
        # Answer first: pyserial discards input that arrives while it opens the port.
        await link.read()
        await link.write(b"#")

    async with (
        await serve_tcp(hang_up) as server,
        await open_serial(f"socket://127.0.0.1:{server.port}") as link,
    ):
        await link.write(b"?")
        assert await asyncio.wait_for(link.read(), 2.0) == b"#"
        with pytest.raises(LinkClosedError):
            await asyncio.wait_for(link.read(), 2.0)


async def test_loop_url_echoes_what_is_written() -> None:
    async with await open_serial("loop://", 9600, stopbits=2) as link:
        assert link.port.stopbits == 2
        await link.write(b"P\x01\x10\xfe")
        assert await asyncio.wait_for(link.read_exactly(4), 2.0) == b"P\x01\x10\xfe"
        await link.write(b"x" * 3000)
        assert await asyncio.wait_for(link.read_exactly(3000), 2.0) == b"x" * 3000


async def test_closing_a_threaded_port_wakes_its_reader_promptly() -> None:
    link = await open_serial("loop://")
    pending = asyncio.create_task(link.read())
    await asyncio.sleep(0.02)
    await asyncio.wait_for(link.close(), 1.0)
    with pytest.raises(LinkClosedError):
        await asyncio.wait_for(pending, 1.0)
    with pytest.raises(LinkClosedError):
        await link.write(b"x")


async def test_a_missing_device_is_named_with_a_hint() -> None:
    with pytest.raises(LinkOpenError, match="/dev/ttyNOPE0: no such device") as caught:
        await open_serial("/dev/ttyNOPE0")
    assert caught.value.port == "/dev/ttyNOPE0"
    assert "list_ports" in caught.value.hint


async def test_a_refused_socket_url_is_reported() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(LinkOpenError, match=f"socket://127.0.0.1:{port}: connection refused"):
        await open_serial(f"socket://127.0.0.1:{port}")


async def test_an_unknown_url_protocol_and_bad_settings_are_spec_errors() -> None:
    with pytest.raises(LinkSpecError, match="nosuch://x"):
        await open_serial("nosuch://x")
    with pytest.raises(LinkSpecError, match="stop bit"):
        await open_serial("loop://", stopbits=3)


@pytest.mark.parametrize(
    ("code", "reason", "hint_word"),
    [
        (errno.EACCES, "permission denied", "dialout"),
        (errno.EBUSY, "port busy", "another program"),
        (errno.ENOENT, "no such device", "list_ports"),
    ],
)
def test_pyserial_open_errors_become_advice(code: int, reason: str, hint_word: str) -> None:
    # Real pyserial exceptions as its open() raises them (as root we cannot provoke EACCES).
    raised = serial.SerialException(code, f"could not open port /dev/ttyUSB0: [Errno {code}]")
    error = _open_error("/dev/ttyUSB0", raised)
    assert str(error).startswith(f"cannot open /dev/ttyUSB0: {reason} — ")
    assert hint_word in error.hint


async def test_concurrent_closes_release_the_port_once() -> None:
    """A reader that meets the end of the stream and a disconnect close the link at the same
    time: the port's descriptor must be closed once. Closed twice, the second close fails with
    EBADF (seen in the suite) or, worse, closes whatever file has reused the number meanwhile."""
    for _ in range(20):
        device = await open_pty()
        link = await open_serial(device.path)
        outcomes = await asyncio.gather(link.close(), link.close(), return_exceptions=True)
        await device.close()
        assert list(outcomes) == [None, None]
