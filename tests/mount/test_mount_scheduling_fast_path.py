"""``WireScheduler.try_take``: the queue-less turn a driver takes on a free wire (issue #14 part
2: CPU per command) never jumps the queue, and hands the wire on like an ordinary turn."""

from __future__ import annotations

import asyncio

from scopelink.mount import Priority, WireScheduler


def test_a_free_wire_is_taken_without_waiting_and_released() -> None:
    scheduler = WireScheduler()
    assert scheduler.try_take()
    assert scheduler.busy
    assert not scheduler.try_take()  # one holder at a time
    scheduler.release()
    assert scheduler.try_take()  # free again


async def test_try_take_never_jumps_the_queue_and_release_passes_the_wire_on() -> None:
    scheduler = WireScheduler()
    assert scheduler.try_take()
    got_it: list[str] = []

    async def wait_for_the_wire() -> None:
        await scheduler.take(Priority.POLL)
        got_it.append("waiter")

    waiter = asyncio.create_task(wait_for_the_wire())
    await asyncio.sleep(0)  # the waiter runs up to its wait
    assert scheduler.waiting(Priority.POLL) == 1
    scheduler.release()  # granted to the waiter directly: the wire stays busy
    assert scheduler.busy
    assert not scheduler.try_take()  # a newcomer does not overtake the waiter
    await waiter
    assert got_it == ["waiter"]
    scheduler.release()
    assert not scheduler.busy
