"""In-memory link pairs: delivery both ways, closing, cancellation safety, draining."""

import asyncio

import pytest

from scopelink.links import LinkClosedError, memory_pair


async def test_bytes_flow_both_ways() -> None:
    pc, mount = memory_pair(("pc", "mount"))
    await pc.write(b":e1\r")
    assert await mount.read_exactly(4) == b":e1\r"
    await mount.write(b"=0123456#")
    assert await pc.read_exactly(9) == b"=0123456#"
    assert (pc.name, mount.name) == ("pc", "mount")


async def test_any_bytes_like_object_can_be_written_and_empty_writes_send_nothing() -> None:
    a, b = memory_pair()
    await a.write(b"")
    await a.write(bytearray(b"ab"))
    await a.write(memoryview(b"xcd")[1:])
    assert await b.read() == b"abcd"


async def test_read_returns_at_most_max_bytes_and_keeps_the_rest() -> None:
    a, b = memory_pair()
    await a.write(b"abcdef")
    assert await b.read(4) == b"abcd"
    assert await b.read(4) == b"ef"


async def test_closing_one_end_delivers_pending_bytes_then_ends_the_other() -> None:
    a, b = memory_pair()
    await a.write(b"last words")
    await a.close()
    assert await b.read() == b"last words"
    with pytest.raises(LinkClosedError, match="other end closed"):
        await b.read()
    assert b.closed
    with pytest.raises(LinkClosedError):
        await a.read()


async def test_writing_to_a_closed_peer_raises() -> None:
    a, b = memory_pair()
    await b.close()
    with pytest.raises(LinkClosedError, match="other end is closed"):
        await a.write(b"x")


async def test_close_wakes_a_pending_read() -> None:
    a, _b = memory_pair()
    pending = asyncio.create_task(a.read())
    await asyncio.sleep(0.01)
    await a.close()
    with pytest.raises(LinkClosedError):
        await asyncio.wait_for(pending, 1.0)


async def test_a_cancelled_read_loses_no_bytes() -> None:
    a, b = memory_pair()
    with pytest.raises(TimeoutError):
        async with asyncio.timeout(0.02):
            await b.read()
    await a.write(b"K")
    assert await b.read() == b"K"


async def test_drain_input_discards_until_quiet() -> None:
    a, b = memory_pair()

    async def chatter() -> None:
        for _ in range(5):
            await a.write(b"##")
            await asyncio.sleep(0.01)

    talker = asyncio.create_task(chatter())
    await asyncio.sleep(0.005)
    # Quiet means 0.3 s without a byte, far above the talker's 10 ms: a stall of a loaded
    # machine fires both timers at once and must not end the drain before the talk ends.
    discarded = await b.drain_input(quiet_seconds=0.3)
    await talker
    assert discarded == b"##" * 5
    await a.write(b"fresh")
    assert await b.read() == b"fresh"


async def test_drain_input_gives_up_on_a_line_that_never_falls_silent() -> None:
    a, b = memory_pair()

    async def babble() -> None:
        while True:
            await a.write(b"\x00")
            await asyncio.sleep(0.005)

    babbler = asyncio.create_task(babble())
    try:
        started = asyncio.get_running_loop().time()
        discarded = await b.drain_input(quiet_seconds=0.05, max_seconds=0.2)
        elapsed = asyncio.get_running_loop().time() - started
    finally:
        babbler.cancel()
    assert 0.2 <= elapsed < 1.0  # gave up at max_seconds (a stall may add to it)
    assert len(discarded) >= 5  # ~40 on a quiet machine
    assert set(discarded) == {0}


async def test_context_manager_closes_and_zero_byte_reads_are_refused() -> None:
    async with memory_pair()[0] as link:
        with pytest.raises(ValueError, match="at least 1"):
            await link.read(0)
    assert link.closed
    with pytest.raises(LinkClosedError, match="is closed"):
        await link.write(b"x")
