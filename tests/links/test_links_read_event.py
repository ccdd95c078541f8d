"""``Link.read_event``: a parser fed as bytes arrive, its reader woken once with the result, in
the producer's call when no task runs (``links.prompt.resolve``), over memory, TCP and paced
links."""

import asyncio
import contextvars

import pytest

from scopelink.links import Link, LinkClosedError, memory_pair, open_link, paced, serve_tcp
from scopelink.links.prompt import fail, resolve
from scopelink.protocol.base import NEED_DATA, NeedData


class UntilHash:
    """Collects bytes up to ``#``; records every chunk it was given."""

    def __init__(self) -> None:
        self.chunks: list[bytes] = []
        self.pending = b""

    def __call__(self, data: bytes) -> bytes | NeedData:
        self.chunks.append(data)
        self.pending += data
        if b"#" not in self.pending:
            return NEED_DATA
        reply, _, self.pending = self.pending.partition(b"#")
        return reply


async def test_the_parser_gets_every_chunk_and_later_bytes_wait_for_the_next_read() -> None:
    pc, device = memory_pair()
    parse = UntilHash()
    await device.write(b"12")  # buffered before the read: parsed first
    reading = asyncio.ensure_future(pc.read_event(parse))
    await asyncio.sleep(0)
    await device.write(b"34")
    await asyncio.sleep(0)
    assert not reading.done()
    await device.write(b"#")
    assert await reading == b"1234"
    assert parse.chunks == [b"12", b"34", b"#"]
    assert pc.bytes_read == 5
    await device.write(b"56#")
    assert await pc.read() == b"56#"  # no parser any more: plain bytes


async def test_a_cancelled_read_event_loses_no_later_bytes_and_the_end_closes_the_link() -> None:
    pc, device = memory_pair()
    parse = UntilHash()
    with pytest.raises(TimeoutError):
        async with asyncio.timeout(0.01):
            await pc.read_event(parse)
    await device.write(b"late#")
    assert await pc.read() == b"late#"
    assert parse.chunks == []
    reading = asyncio.ensure_future(pc.read_event(parse))
    await asyncio.sleep(0)
    await device.close()
    with pytest.raises(LinkClosedError, match="other end closed"):
        await reading
    assert pc.closed
    with pytest.raises(LinkClosedError):
        await pc.read_event(parse)


async def test_over_tcp_and_a_paced_link_the_reader_gets_whole_replies() -> None:
    async def answer(link: Link) -> None:
        while True:
            command = await link.read(1)
            await link.write(command + b"abc#")

    async with await serve_tcp(answer) as server:
        url = f"tcp://127.0.0.1:{server.port}"
        for link in (await open_link(url), paced(await open_link(url), 96000)):
            parse = UntilHash()
            for letter in (b"e", b"L"):
                await link.write(letter)
                assert await link.read_event(parse) == letter + b"abc"
            assert link.bytes_read == 10
            await link.close()


async def test_resolve_wakes_the_task_inside_the_call_unless_a_task_resolves() -> None:
    loop = asyncio.get_running_loop()
    marks: list[str] = []
    variable = contextvars.ContextVar("variable", default="unset")

    async def waiter(future: asyncio.Future[int]) -> int:
        variable.set("the waiter's")
        value = await future
        marks.append(f"woke with {value} in {variable.get()} context")
        return value

    # From a plain callback (a transport's data_received): the task runs inside resolve().
    future: asyncio.Future[int] = loop.create_future()
    task = asyncio.ensure_future(waiter(future))
    await asyncio.sleep(0)

    def resolve_from_callback() -> None:
        marks.append("resolving")
        resolve(future, 1)
        marks.append("resolved")

    loop.call_soon(resolve_from_callback)
    assert await task == 1
    assert marks == ["resolving", "woke with 1 in the waiter's context", "resolved"]

    # From inside a task (a memory link fed by its peer's write): scheduled, as set_result.
    marks.clear()
    future = loop.create_future()
    task = asyncio.ensure_future(waiter(future))
    await asyncio.sleep(0)
    resolve(future, 2)
    marks.append("resolved")
    assert await task == 2
    assert marks == ["resolved", "woke with 2 in the waiter's context"]

    # Several callbacks (two tasks and a plain one): each runs once, in the order added.
    marks.clear()
    future = loop.create_future()
    future.add_done_callback(lambda done: marks.append(f"callback saw {done.result()}"))
    tasks = [asyncio.ensure_future(waiter(future)) for _ in range(2)]
    await asyncio.sleep(0)
    loop.call_soon(resolve, future, 3)
    assert await asyncio.gather(*tasks) == [3, 3]
    assert marks == ["callback saw 3"] + ["woke with 3 in the waiter's context"] * 2

    # A callback that fails is reported as the loop reports one, not raised into the producer.
    reported: list[str] = []
    loop.set_exception_handler(lambda _loop, context: reported.append(context["message"]))
    try:
        future = loop.create_future()
        future.add_done_callback(lambda _done: 1 / 0)
        loop.call_soon(resolve, future, 4)
        await asyncio.sleep(0)
        await asyncio.sleep(0)
    finally:
        loop.set_exception_handler(None)
    assert len(reported) == 1
    assert reported[0].startswith("Exception in callback")

    # A failure reaches the task; a cancelled task stops waiting.
    future = loop.create_future()
    task = asyncio.ensure_future(waiter(future))
    await asyncio.sleep(0)
    loop.call_soon(fail, future, LinkClosedError("gone"))
    with pytest.raises(LinkClosedError, match="gone"):
        await task
    future = loop.create_future()
    task = asyncio.ensure_future(waiter(future))
    await asyncio.sleep(0)
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert future.cancelled()
