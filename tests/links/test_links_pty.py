"""Pseudo-terminal links, opened from the other side by real programs: socat and pyserial."""

import asyncio
import contextlib
import os
import random
import shutil
import threading
import time
import tty
from pathlib import Path

import pytest
import serial

from scopelink.links import (
    LineSettings,
    Link,
    LinkClosedError,
    LinkOpenError,
    open_pty,
    open_serial,
    serve_tcp,
)

SOCAT = shutil.which("socat")


async def test_socat_bridges_the_pty_to_tcp_both_ways() -> None:
    if SOCAT is None:
        pytest.skip("socat is not installed (scripts/test.sh installs it)")
    received: asyncio.Queue[bytes] = asyncio.Queue()
    tcp_side: asyncio.Future[Link] = asyncio.get_running_loop().create_future()

    async def collect(link: Link) -> None:
        tcp_side.set_result(link)
        while True:
            await received.put(await link.read())

    async with await serve_tcp(collect) as server, await open_pty() as pty:
        socat = await asyncio.create_subprocess_exec(
            SOCAT,
            f"OPEN:{pty.path},raw,echo=0,b9600,cs8,cstopb=1",
            f"TCP:127.0.0.1:{server.port}",
        )
        try:
            bridge = await asyncio.wait_for(tcp_side, 5.0)
            await pty.write(b":e1\r")
            got = b""
            while len(got) < 4:
                got += await asyncio.wait_for(received.get(), 5.0)
            assert got == b":e1\r"
            await bridge.write(b"=030507\r\x00\xff")
            assert await asyncio.wait_for(pty.read_exactly(10), 5.0) == b"=030507\r\x00\xff"
            assert pty.line_settings() == LineSettings(9600, 8, "N", 2)
        finally:
            socat.terminate()
            await socat.wait()


async def test_pyserial_opens_the_slave_path_directly() -> None:
    async with await open_pty() as pty, await open_serial(pty.path) as client:
        assert pty.path.startswith("/dev/pts/")
        assert pty.name == f"pty {pty.path}"
        await client.write(b"Q")
        assert await asyncio.wait_for(pty.read(), 2.0) == b"Q"
        await pty.write(b"A\r\n\x03")  # raw: no CR/LF translation, no signals, no echo
        assert await asyncio.wait_for(client.read_exactly(4), 2.0) == b"A\r\n\x03"
        with pytest.raises(TimeoutError):
            await asyncio.wait_for(pty.read(), 0.05)


async def test_a_serial_client_may_read_before_the_device_answers() -> None:
    # pyserial leaves a tty at VMIN=0, where "no data yet" reads as empty: that is not the end.
    async with await open_pty() as pty, await open_serial(pty.path) as client:
        pending = asyncio.create_task(client.read())
        await asyncio.sleep(0.1)
        assert not pending.done(), "an empty tty read was taken for end of stream"
        await pty.write(b"042507#")
        assert await asyncio.wait_for(pending, 2.0) == b"042507#"
        assert not client.closed


async def test_back_to_back_exchanges_are_never_taken_for_a_hang_up() -> None:
    """A driver writes a command and reads its reply, again and again. The client's descriptor
    stays watched between reads, so a readiness report queued before one read took its bytes
    can wake the next read before the device has answered: on a VMIN=0 tty that read is empty,
    which is not the end of the stream. The device answers from another thread, as a real one
    answers from another machine (in this loop it would answer too soon to show it)."""
    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)

    def device() -> None:
        # The client's next read starts before the reply is in; the reply lands anywhere in
        # the next 0.2 ms, so some land between an empty read and the readiness check after it
        # (a reply there was taken for a hang-up: CI, 2026-11-25). Busy-waited: a sleep is too
        # coarse to reach that window.
        jitter = random.Random(1)
        with contextlib.suppress(OSError):  # EIO once the client has closed: done
            while command := os.read(master, 16):
                answer_at = time.perf_counter() + jitter.uniform(0.0, 0.0002)
                while time.perf_counter() < answer_at:
                    pass
                os.write(master, command)

    answering = threading.Thread(target=device, daemon=True)
    answering.start()
    try:
        async with await open_serial(path) as client:
            for index in range(3000):
                command = bytes([0x41 + index % 26])
                await client.write(command)
                async with asyncio.timeout(2.0):  # in this task, as a driver reads
                    assert await client.read() == command
            assert not client.closed
    finally:
        os.close(slave)
        os.close(master)
        answering.join(2.0)


async def test_a_serial_client_sees_the_device_go_away() -> None:
    pty = await open_pty()
    async with await open_serial(pty.path) as client:
        pending = asyncio.create_task(client.read())
        await asyncio.sleep(0.05)
        await pty.close()
        with pytest.raises(LinkClosedError):
            await asyncio.wait_for(pending, 2.0)


async def test_line_settings_follow_what_the_client_sets() -> None:
    async with await open_pty() as pty:
        assert pty.line_settings() == LineSettings(9600, 8, "N", 1)
        client = await asyncio.to_thread(serial.Serial, pty.path, 9600, stopbits=2)
        try:
            settings = pty.line_settings()
            assert settings == LineSettings(9600, 8, "N", 2)
            assert settings.bits_per_byte == 11
            assert str(settings) == "9600 8N2"
            # Linux ptys keep the speed and stop bits, but refuse data bits other than 8 and
            # drop the parity flag, so only those two can be checked here.
            client.baudrate = 4800
            client.stopbits = 1
            assert pty.line_settings() == LineSettings(4800, 8, "N", 1)
            assert pty.line_settings().bits_per_byte == 10
        finally:
            client.close()


async def test_the_client_can_close_and_reopen_without_ending_our_stream() -> None:
    async with await open_pty() as pty:
        for attempt in (b"first", b"second"):
            async with await open_serial(pty.path) as client:
                await client.write(attempt)
                assert await asyncio.wait_for(pty.read_exactly(len(attempt)), 2.0) == attempt
                await pty.write(attempt.upper())
                assert await asyncio.wait_for(client.read_exactly(len(attempt)), 2.0) == (
                    attempt.upper()
                )
            with pytest.raises(TimeoutError):  # quiet, not end-of-stream, while nobody has it open
                await asyncio.wait_for(pty.read(), 0.05)
            assert not pty.closed


async def test_a_stable_symlink_points_at_the_slave_and_goes_away_on_close(
    tmp_path: Path,
) -> None:
    link_path = tmp_path / "ttySynScan"
    link_path.symlink_to("/dev/pts/stale-from-an-earlier-run")
    pty = await open_pty(link_path)
    assert pty.path == str(link_path)
    assert os.readlink(link_path) == pty.device_path
    assert pty.name == f"pty {link_path} -> {pty.device_path}"
    async with await open_serial(pty.path) as client:
        await pty.write(b"v4.0    ")
        assert await asyncio.wait_for(client.read_exactly(8), 2.0) == b"v4.0    "
    await pty.close()
    assert not link_path.is_symlink()


async def test_a_regular_file_is_never_replaced_by_the_symlink(tmp_path: Path) -> None:
    precious = tmp_path / "notes.txt"
    precious.write_text("keep me")
    with pytest.raises(LinkOpenError, match="not a symlink"):
        await open_pty(precious)
    assert precious.read_text() == "keep me"


async def test_close_wakes_a_pending_read() -> None:
    pty = await open_pty()
    pending = asyncio.create_task(pty.read())
    await asyncio.sleep(0.01)
    await pty.close()
    with pytest.raises(LinkClosedError):
        await asyncio.wait_for(pending, 1.0)
