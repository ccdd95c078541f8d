"""Wire pacing: measured throughput over memory and TCP links matches the line rate."""

import asyncio
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

import pytest

from scopelink.links import Link, memory_pair, open_tcp, paced, serve_tcp

pytestmark = pytest.mark.solo  # wire timing against the clock: runs alone (tests/README.md)

BAUD = 9600


@asynccontextmanager
async def memory_link_pair() -> AsyncIterator[tuple[Link, Link]]:
    sender, receiver = memory_pair()
    async with sender, receiver:
        yield sender, receiver


@asynccontextmanager
async def tcp_link_pair() -> AsyncIterator[tuple[Link, Link]]:
    accepted: asyncio.Queue[Link] = asyncio.Queue()
    done = asyncio.Event()

    async def hand_over(link: Link) -> None:
        await accepted.put(link)
        await done.wait()

    async with (
        await serve_tcp(hand_over) as server,
        await open_tcp("127.0.0.1", server.port) as sender,
    ):
        receiver = await asyncio.wait_for(accepted.get(), 2.0)
        yield sender, receiver
        done.set()


PAIRS = {"memory": memory_link_pair, "tcp": tcp_link_pair}


async def receive(link: Link, count: int, arrivals: list[tuple[float, int]]) -> None:
    """Read ``count`` bytes, noting (time, bytes so far) at each arrival."""
    total = 0
    while total < count:
        total += len(await link.read())
        arrivals.append((time.monotonic(), total))


@pytest.mark.parametrize("bits_per_byte", [10, 11])
@pytest.mark.parametrize("pair", sorted(PAIRS))
async def test_a_burst_leaves_at_the_line_rate(pair: str, bits_per_byte: int) -> None:
    count = 800
    byte_seconds = bits_per_byte / BAUD
    async with PAIRS[pair]() as (sender, receiver):
        line = paced(sender, BAUD, bits_per_byte)
        arrivals: list[tuple[float, int]] = []
        reader = asyncio.create_task(receive(receiver, count, arrivals))
        started = time.monotonic()
        await line.write(bytes(range(256)) * 3 + bytes(32))
        written = time.monotonic()
        await asyncio.wait_for(reader, 5.0)
    expected = count * byte_seconds
    assert written - started == pytest.approx(expected, rel=0.02)
    assert arrivals[-1][0] - started == pytest.approx(expected, rel=0.02)
    # Never early: byte k may arrive only once k + 1 byte-times have passed.
    for arrived_at, so_far in arrivals:
        assert arrived_at - started >= so_far * byte_seconds - 1e-4


async def test_back_to_back_small_writes_do_not_drift() -> None:
    byte_seconds = 10 / BAUD
    async with memory_link_pair() as (sender, receiver):
        line = paced(sender, BAUD, 10)
        reader = asyncio.create_task(receive(receiver, 800, []))
        started = time.monotonic()
        # Each write's last timer wakes up to 1 ms late; 100 of those would add up to 12 %.
        for _ in range(100):
            await line.write(b":j1\r:j2\r")
        elapsed = time.monotonic() - started
        await reader
    # Never early; late by less than half of what drift would add (12 %): a loaded machine
    # (the suite runs on two workers) wakes timers a few ms late once or twice, never 100 times.
    assert 800 * byte_seconds * 0.99 <= elapsed <= 800 * byte_seconds * 1.06


async def test_an_idle_line_banks_no_credit() -> None:
    byte_seconds = 11 / BAUD
    async with memory_link_pair() as (sender, receiver):
        line = paced(sender, BAUD, 11)
        await line.write(b"Q")
        await asyncio.sleep(0.3)  # idle long enough to have "earned" 260 bytes
        reader = asyncio.create_task(receive(receiver, 1 + 400, []))
        started = time.monotonic()
        await line.write(b"R" * 400)
        elapsed = time.monotonic() - started
        await reader
    assert elapsed == pytest.approx(400 * byte_seconds, rel=0.02)


async def test_concurrent_writers_queue_rather_than_interleave() -> None:
    async with memory_link_pair() as (sender, receiver):
        line = paced(sender, 96000, 10)
        await asyncio.gather(line.write(b"a" * 50), line.write(b"b" * 50))
        received = await receiver.read_exactly(100)
    assert received in (b"a" * 50 + b"b" * 50, b"b" * 50 + b"a" * 50)


async def test_paced_link_keeps_the_name_reads_through_and_closes_the_inner_link() -> None:
    sender, receiver = memory_pair(("pc", "scope"))
    line = paced(sender, BAUD, 11)
    assert line.name == "pc"
    assert (line.baudrate, line.bits_per_byte) == (BAUD, 11)
    await receiver.write(b"A")
    assert await line.read() == b"A"
    await line.close()
    assert sender.closed
    with pytest.raises(ValueError, match="positive"):
        paced(receiver, 0, 10)


async def exchange_loop(client: Link, server: Link, rounds: int, *, think_s: float = 0.0) -> float:
    """Seconds for ``rounds`` one-byte requests each answered with 18 bytes (a SynScan ``e``)."""

    async def answer() -> None:
        for _ in range(rounds):
            await server.read_exactly(1)
            if think_s:
                await asyncio.sleep(think_s)
            await server.write(b"0" * 17 + b"#")

    responder = asyncio.create_task(answer())
    started = time.monotonic()
    for _ in range(rounds):
        await client.write(b"e")
        await client.read_exactly(18)
    elapsed = time.monotonic() - started
    await responder
    return elapsed


async def test_a_request_response_loop_never_beats_the_line() -> None:
    """Both ends paced: each round trip takes at least 19 byte-times, and not much more."""
    byte_seconds = 10 / BAUD
    rounds = 40
    async with memory_link_pair() as (pc, device):
        elapsed = await exchange_loop(paced(pc, BAUD, 10), paced(device, BAUD, 10), rounds)
    line_time = rounds * 19 * byte_seconds
    assert elapsed >= line_time - 1e-3
    assert elapsed < line_time * 1.25


async def test_a_slow_answer_banks_no_credit() -> None:
    """A device that thinks for 30 ms still sends its 18 bytes at the line rate after that."""
    byte_seconds = 10 / BAUD
    rounds = 5
    async with memory_link_pair() as (pc, device):
        elapsed = await exchange_loop(
            paced(pc, BAUD, 10), paced(device, BAUD, 10), rounds, think_s=0.03
        )
    assert elapsed >= rounds * (19 * byte_seconds + 0.03) - 1e-3


def test_the_precise_loop_keeps_a_paced_exchange_close_to_the_line() -> None:
    """On the select()-based loop the timers are not rounded up to whole milliseconds: the loop
    still never beats the line, and loses less to timer overshoot."""
    import selectors

    from scopelink.links import precise_event_loop

    byte_seconds = 10 / BAUD
    rounds = 40

    async def measure() -> float:
        loop = asyncio.get_running_loop()
        assert isinstance(loop, asyncio.SelectorEventLoop)
        assert isinstance(loop._selector, selectors.SelectSelector)  # type: ignore[attr-defined]
        async with memory_link_pair() as (pc, device):
            return await exchange_loop(paced(pc, BAUD, 10), paced(device, BAUD, 10), rounds)

    with asyncio.Runner(loop_factory=precise_event_loop) as runner:
        elapsed = runner.run(measure())
    line_time = rounds * 19 * byte_seconds
    assert line_time - 1e-3 <= elapsed < line_time * 1.15


async def test_a_batched_write_hands_bytes_over_in_groups_never_early_last_on_time() -> None:
    """batch_s=16 ms: a 100-ms write arrives in at most 8 groups (not 96 single bytes), no byte
    before its time on the line, the last exactly when the line would have carried it."""
    byte_seconds = 10 / BAUD
    count = 96
    async with memory_link_pair() as (sender, receiver):
        line = paced(sender, BAUD, 10, batch_s=0.016)
        arrivals: list[tuple[float, int]] = []
        reader = asyncio.create_task(receive(receiver, count, arrivals))
        started = time.monotonic()
        await line.write(bytes(count))
        written = time.monotonic()
        await asyncio.wait_for(reader, 5.0)
    expected = count * byte_seconds
    assert written - started == pytest.approx(expected, rel=0.02)
    assert arrivals[-1][0] - started == pytest.approx(expected, rel=0.02)
    # Hand-overs are at least 16 ms apart, the final one aside: ceil(100 / 16) + 1 at most.
    assert 2 <= len(arrivals) <= 8, arrivals
    for arrived_at, so_far in arrivals:
        assert arrived_at - started >= so_far * byte_seconds - 1e-4


async def test_a_batched_request_response_loop_never_beats_the_line() -> None:
    """The SynScan emulator's wire (replies batched every 16 ms): a poll still takes its 19
    byte-times, as on the unbatched line."""
    byte_seconds = 10 / BAUD
    rounds = 20
    async with memory_link_pair() as (pc, device):
        elapsed = await exchange_loop(
            paced(pc, BAUD, 10), paced(device, BAUD, 10, batch_s=0.016), rounds
        )
    line_time = rounds * 19 * byte_seconds
    assert elapsed >= line_time - 1e-3
    assert elapsed < line_time * 1.25


def test_the_batch_is_bounded() -> None:
    sender, _ = memory_pair()
    with pytest.raises(ValueError, match="batch_s"):
        paced(sender, BAUD, 10, batch_s=-0.001)
    with pytest.raises(ValueError, match="batch_s"):
        paced(sender, BAUD, 10, batch_s=0.5)


def test_the_synscan_emulator_wire_batches_like_a_usb_serial_adapter() -> None:
    from scopelink.servers.hosting import SERIAL_9600_8N1, USB_SERIAL_BATCH_S

    assert (SERIAL_9600_8N1.baudrate, SERIAL_9600_8N1.bits_per_byte) == (9600, 10)
    assert SERIAL_9600_8N1.batch_s == USB_SERIAL_BATCH_S == 0.016


async def test_a_late_reader_loses_no_line_time_over_a_memory_pair() -> None:
    """A device whose reader gets round to a request after it arrived (a busy event loop with 100
    emulators) answers on the line's schedule: the paced peer says when the line carried the
    request, and a reply written within 5 ms of that starts then, not when the request was read."""
    async with memory_link_pair() as (pc, device):
        client, server = paced(pc, BAUD, 10), paced(device, BAUD, 10)
        await client.write(b"e")
        carried_at = client._line_free_at  # when the line finished carrying the 'e'
        await asyncio.sleep(0.003)  # busy elsewhere
        read_at = time.monotonic()
        assert await server.read_exactly(1) == b"e"
    assert read_at - carried_at >= 0.003
    # The request counts as arrived when the line carried it, not when it was read...
    assert server._input_at == carried_at
    # ... so a reply asked for 2 ms later still starts right then (a device with no latency),
    # and one asked for after 5 ms starts when asked (the program's delay is then real).
    assert server._start_of(carried_at + 0.002) == carried_at
    assert server._start_of(carried_at + 0.006) == carried_at + 0.006


def test_the_docs_state_the_batching_and_reuse_defaults_the_code_uses() -> None:
    """Docs and code agree on the new defaults: the emulator wire's batch, its bound, and the
    astrometry context reuse windows."""
    from pathlib import Path

    from scopelink.astro import frames, horizontal
    from scopelink.links.pacing import MAX_BATCH_SECONDS
    from scopelink.servers.hosting import USB_SERIAL_BATCH_S

    docs = Path(__file__).resolve().parents[2] / "docs"
    links = (docs / "links.md").read_text()
    emulators = (docs / "emulators.md").read_text()
    astronomy = (docs / "astronomy.md").read_text()
    batch_ms = f"{USB_SERIAL_BATCH_S * 1000:g} ms"
    assert f"default 0, at most {MAX_BATCH_SECONDS:g} s" in links
    assert batch_ms in links
    assert f"every {batch_ms}" in emulators
    assert f"within **{frames._REUSE_WITHIN_DAYS * 86400:g} s**" in astronomy
    assert f"within {horizontal._REUSE_WITHIN_DAYS * 86400:g} s of the last" in astronomy
