"""Property: any bytes, written in any chunking, arrive intact and in order (memory and TCP)."""

import asyncio

from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.links import Link, memory_pair, open_tcp, serve_tcp

chunks = st.lists(st.binary(min_size=1, max_size=300), max_size=20)
read_sizes = st.lists(st.integers(min_value=1, max_value=64), min_size=1, max_size=10)


async def send_and_collect(
    sender: Link, receiver: Link, parts: list[bytes], sizes: list[int]
) -> bytes:
    expected = sum(map(len, parts))

    async def send() -> None:
        for part in parts:
            await sender.write(part)

    async def collect() -> bytes:
        received = bytearray()
        while len(received) < expected:
            received += await receiver.read(sizes[len(received) % len(sizes)])
        return bytes(received)

    _, received = await asyncio.wait_for(asyncio.gather(send(), collect()), 5.0)
    return received


@settings(max_examples=60, deadline=None)
@given(parts=chunks, sizes=read_sizes)
def test_memory_pair_delivers_every_byte_in_order(parts: list[bytes], sizes: list[int]) -> None:
    async def run() -> bytes:
        sender, receiver = memory_pair()
        async with sender, receiver:
            return await send_and_collect(sender, receiver, parts, sizes)

    assert asyncio.run(run()) == b"".join(parts)


@settings(max_examples=30, deadline=None)
@given(parts=chunks, sizes=read_sizes)
def test_tcp_delivers_every_byte_in_order(parts: list[bytes], sizes: list[int]) -> None:
    async def run() -> bytes:
        accepted: asyncio.Queue[Link] = asyncio.Queue()
        finished = asyncio.Event()

        async def hand_over(link: Link) -> None:
            await accepted.put(link)
            await finished.wait()

        async with await serve_tcp(hand_over) as server:
            async with await open_tcp("127.0.0.1", server.port) as sender:
                receiver = await accepted.get()
                received = await send_and_collect(sender, receiver, parts, sizes)
            finished.set()
            return received

    assert asyncio.run(run()) == b"".join(parts)
