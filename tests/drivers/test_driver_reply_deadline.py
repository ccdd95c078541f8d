"""``drivers.common.ReplyDeadline``: the reply timeout both drivers' wires use (issue #14 part 2:
one timer handle for many exchanges instead of an ``asyncio.timeout`` per exchange), with the
same outcomes as ``asyncio.timeout``: a late reply times out, a stop cuts a read short, a
cancellation from elsewhere stays a cancellation."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Any

import pytest

from scopelink.drivers.common import ReplyDeadline


async def reading_forever(deadline: ReplyDeadline, seconds: float | None) -> asyncio.Task[None]:
    """A task inside ``deadline.start(seconds)`` waiting for a reply that never comes, once it
    is waiting."""
    reading = asyncio.Event()

    async def read() -> None:
        with deadline.start(seconds):
            reading.set()
            await asyncio.get_running_loop().create_future()

    task = asyncio.create_task(read())
    await reading.wait()
    return task


async def test_a_reply_later_than_the_timeout_leaves_with_timeout_error() -> None:
    deadline = ReplyDeadline()
    never = asyncio.get_running_loop().create_future()
    started = time.monotonic()
    with pytest.raises(TimeoutError), deadline.start(0.05):
        await never
    assert 0.04 <= time.monotonic() - started < 2.0
    assert not deadline.interrupted
    assert not deadline.active


async def test_a_reply_in_time_is_returned_and_a_later_read_still_times_out() -> None:
    deadline = ReplyDeadline()
    loop = asyncio.get_running_loop()
    for _ in range(3):
        reply = loop.create_future()
        loop.call_soon(reply.set_result, b"ok")
        with deadline.start(0.05):
            assert await reply == b"ok"
    await asyncio.sleep(0.08)  # the first read's timer fires with no read in progress
    with pytest.raises(TimeoutError), deadline.start(0.05):
        await loop.create_future()


async def test_many_exchanges_within_the_timeout_arm_one_timer(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    loop = asyncio.get_running_loop()
    armed: list[float] = []
    call_at: Callable[..., asyncio.TimerHandle] = loop.call_at

    def counting_call_at(when: float, callback: Callable[..., object], *args: Any) -> Any:
        armed.append(when)
        return call_at(when, callback, *args)

    monkeypatch.setattr(loop, "call_at", counting_call_at)
    deadline = ReplyDeadline()
    for _ in range(200):
        reply = loop.create_future()
        loop.call_soon(reply.set_result, None)
        with deadline.start(5.0):
            await reply
    assert len(armed) == 1
    deadline.close()


async def test_a_deadline_moved_on_by_later_reads_times_out_at_the_latest_one() -> None:
    """The timer armed by the first read fires before the last read is due: it re-arms for
    that read's own deadline instead of cutting it short."""
    loop = asyncio.get_running_loop()
    deadline = ReplyDeadline()
    with deadline.start(0.1):
        await asyncio.sleep(0)
    await asyncio.sleep(0.06)
    started = loop.time()
    with pytest.raises(TimeoutError), deadline.start(0.1):
        await loop.create_future()
    assert loop.time() - started >= 0.1 - 0.005


async def test_a_stop_interrupts_the_read_in_progress() -> None:
    deadline = ReplyDeadline()
    task = await reading_forever(deadline, None)
    assert deadline.active
    deadline.interrupt()
    with pytest.raises(TimeoutError):
        await task
    assert deadline.interrupted


async def test_an_interrupt_of_a_read_that_completes_at_once_cancels_nothing_later() -> None:
    """The reply was already there: the read ends without waiting, and the interrupt must not
    cancel whatever the task awaits next."""
    deadline = ReplyDeadline()
    with deadline.start(5.0):
        deadline.interrupt()
    await asyncio.sleep(0.01)  # would raise CancelledError if the interrupt had leaked
    task = asyncio.current_task()
    assert task is not None
    assert task.cancelling() == 0


async def test_a_cancellation_from_elsewhere_stays_a_cancellation() -> None:
    deadline = ReplyDeadline()
    task = await reading_forever(deadline, 5.0)
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    assert not deadline.active


async def test_a_cancellation_racing_the_timeout_stays_a_cancellation() -> None:
    """As with ``asyncio.timeout``: the deadline passed, and someone else cancelled too."""
    loop = asyncio.get_running_loop()
    deadline = ReplyDeadline()
    task = await reading_forever(deadline, 0.02)
    deadline.interrupt()  # our cancellation, delivered from the loop next
    loop.call_soon(task.cancel)  # and one from elsewhere right after it
    with pytest.raises(asyncio.CancelledError):
        await task
