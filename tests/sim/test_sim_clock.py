"""SimClock: stepped, accelerated, continuous speed changes, and sleeping in every mode."""

from __future__ import annotations

import asyncio
import time
from datetime import UTC, datetime, timedelta

import pytest

from scopelink.sim import SimClock

START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)


class FakeRealTime:
    """A hand-driven real-time source, to check the clock's arithmetic exactly."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_stepped_clock_moves_only_when_advanced() -> None:
    clock = SimClock.stepped(START)
    assert clock.is_stepped
    assert clock.elapsed() == 0.0
    time.sleep(0.01)
    assert clock.now() == START
    clock.advance(90.5)
    assert clock.elapsed() == 90.5
    assert clock.now() == START + timedelta(seconds=90.5)
    with pytest.raises(ValueError, match="non-negative"):
        clock.advance(-1.0)


def test_now_is_aware_utc() -> None:
    now = SimClock().now()
    assert now.tzinfo is not None
    assert now.utcoffset() == timedelta(0)
    with pytest.raises(ValueError, match="time zone"):
        SimClock(start=datetime(2026, 1, 1))


def test_accelerated_clock_runs_faster() -> None:
    before_start = time.monotonic()
    clock = SimClock.accelerated(100.0, START)
    after_start = time.monotonic()
    time.sleep(0.2)
    before_read = time.monotonic()
    elapsed = clock.elapsed()
    after_read = time.monotonic()
    # Bounds from real readings taken on either side, so a loaded machine cannot fail this.
    assert 100.0 * (before_read - after_start) <= elapsed <= 100.0 * (after_read - before_start)
    assert elapsed >= 19.9
    assert clock.now() > START + timedelta(seconds=19.9)


def test_factor_change_is_continuous() -> None:
    real = FakeRealTime()
    clock = SimClock(start=START, rate=10.0, monotonic=real)
    real.now += 3.0
    assert clock.elapsed() == 30.0
    clock.set_rate(1000.0)
    assert clock.elapsed() == 30.0  # no jump when the factor changes
    real.now += 0.5
    assert clock.elapsed() == 530.0
    clock.set_rate(0.0)  # stepped from here
    real.now += 100.0
    assert clock.elapsed() == 530.0
    clock.advance(1.0)
    clock.set_rate(1.0)
    real.now += 2.0
    assert clock.elapsed() == 533.0


def test_real_factor_change_is_continuous() -> None:
    clock = SimClock.accelerated(50.0, START)
    time.sleep(0.05)
    before = clock.elapsed()
    clock.set_rate(2.0)
    after = clock.elapsed()
    assert 0.0 <= after - before < 0.5


def test_set_time_moves_the_epoch_not_elapsed() -> None:
    clock = SimClock.stepped(START)
    clock.advance(100.0)
    target = datetime(2030, 6, 1, 12, tzinfo=UTC)
    clock.set_time(target)
    assert clock.now() == target
    assert clock.elapsed() == 100.0
    clock.advance(5.0)
    assert clock.now() == target + timedelta(seconds=5)


async def test_stepped_sleep_wakes_when_advanced_past_the_deadline() -> None:
    clock = SimClock.stepped(START)
    sleeper = asyncio.create_task(clock.sleep(10.0))
    await asyncio.sleep(0.01)
    clock.advance(9.0)
    await asyncio.sleep(0.01)
    assert not sleeper.done()
    clock.advance(1.5)
    await asyncio.wait_for(sleeper, 1.0)


async def test_accelerated_sleep_takes_scaled_real_time() -> None:
    clock = SimClock.accelerated(100.0, START)
    real_start = time.monotonic()
    await clock.sleep(10.0)  # 0.1 s real
    real = time.monotonic() - real_start
    assert clock.elapsed() >= 10.0
    assert 0.09 <= real < 1.0


async def test_sleep_follows_a_factor_change_while_waiting() -> None:
    clock = SimClock(start=START, rate=1.0)
    sleeper = asyncio.create_task(clock.sleep(60.0))  # a minute of real time at x1
    await asyncio.sleep(0.02)
    clock.set_rate(10_000.0)  # now about 6 ms
    await asyncio.wait_for(sleeper, 2.0)
    assert clock.elapsed() >= 60.0


async def test_sleep_in_real_time_mode() -> None:
    clock = SimClock(start=START)
    real_start = time.monotonic()
    await clock.sleep(0.05)
    assert time.monotonic() - real_start >= 0.045
    assert clock.elapsed() >= 0.05
