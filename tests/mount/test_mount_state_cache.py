"""The Mount API's state cache, wire scheduling, goto by name with progress, and the blocking
facade — on the real simulated mount (a deliberately failing device only where a fault is the
point)."""

from __future__ import annotations

import asyncio
import threading
from datetime import UTC, datetime

import pytest

from scopelink.astro import Site, angular_separation_deg
from scopelink.astro.catalog import UnknownObjectError, lookup
from scopelink.mount import (
    AlignmentMode,
    Capabilities,
    Identity,
    LimitError,
    Mount,
    MountState,
    ParkPosition,
    Priority,
    SlewProgress,
    WireScheduler,
)
from scopelink.mount.blocking import BlockingMount
from scopelink.sim import EQ6, SimClock, SimulatedMount

SITE = Site(latitude_deg=45.0, longitude_deg=7.0, elevation_m=300.0)
START = datetime(2026, 3, 1, 21, 0, tzinfo=UTC)  # Capella high in the west, Acrux never up


def fast_mount(rate: float = 20.0) -> SimulatedMount:
    return SimulatedMount(EQ6, site=SITE, clock=SimClock(start=START, rate=rate))


def is_polling(mount: Mount) -> bool:
    return mount.poller.running


# --- wire scheduling ----------------------------------------------------------------------------


async def test_waiting_commands_get_the_wire_before_waiting_polls() -> None:
    scheduler = WireScheduler()
    order: list[str] = []
    release = asyncio.Event()

    async def hold_first() -> None:
        async with scheduler.turn(Priority.POLL):
            order.append("poll 0")
            await release.wait()

    async def use(priority: Priority, name: str) -> None:
        async with scheduler.turn(priority):
            order.append(name)
            await asyncio.sleep(0)

    holder = asyncio.create_task(hold_first())
    await asyncio.sleep(0)
    tasks = [
        asyncio.create_task(use(Priority.POLL, "poll 1")),
        asyncio.create_task(use(Priority.POLL, "poll 2")),
        asyncio.create_task(use(Priority.COMMAND, "command 1")),
        asyncio.create_task(use(Priority.COMMAND, "command 2")),
    ]
    await asyncio.sleep(0)
    assert scheduler.busy
    assert scheduler.waiting(Priority.COMMAND) == 2
    assert scheduler.waiting(Priority.POLL) == 2
    release.set()
    await asyncio.gather(holder, *tasks)
    assert order == ["poll 0", "command 1", "command 2", "poll 1", "poll 2"]
    assert not scheduler.busy


async def test_a_cancelled_waiter_does_not_keep_the_wire() -> None:
    scheduler = WireScheduler()
    release = asyncio.Event()
    got_it: list[str] = []

    async def hold() -> None:
        async with scheduler.turn(Priority.POLL):
            await release.wait()

    async def use(name: str) -> None:
        async with scheduler.turn(Priority.COMMAND):
            got_it.append(name)

    holder = asyncio.create_task(hold())
    await asyncio.sleep(0)
    cancelled = asyncio.create_task(use("cancelled"))
    later = asyncio.create_task(use("later"))
    await asyncio.sleep(0)
    cancelled.cancel()
    release.set()
    await holder
    await later
    with pytest.raises(asyncio.CancelledError):
        await cancelled
    assert got_it == ["later"]
    assert not scheduler.busy


# --- the state cache ----------------------------------------------------------------------------


async def test_the_poller_runs_only_while_someone_watches() -> None:
    mount = fast_mount(rate=1.0)
    await mount.connect()
    first = mount.state.read_at
    await asyncio.sleep(0.2)
    assert mount.state.read_at == first, "nobody watches: nothing polls"
    async with mount.watching():
        async with mount.watching():
            await asyncio.sleep(0.3)
        assert is_polling(mount)
        polls = mount.poller.polls
        # 20 Hz for the simulator: about 6 polls in 0.3 s, never a busy loop
        assert 2 <= polls <= 12
    assert not is_polling(mount)
    assert mount.state.read_at > first
    settled = mount.poller.polls
    await asyncio.sleep(0.2)
    assert mount.poller.polls == settled


async def test_states_and_wait_for_follow_the_mount() -> None:
    mount = fast_mount()
    await mount.connect()
    seen: list[MountState] = []
    async with asyncio.timeout(5):
        async for state in mount.states():
            seen.append(state)
            if len(seen) == 3:
                break
    assert seen[0].read_at < seen[1].read_at < seen[2].read_at
    with pytest.raises(TimeoutError):
        await mount.wait_for(lambda state: state.parked, timeout_s=0.2)
    await asyncio.sleep(0.1)
    assert not mount.poller.running, "a finished wait_for leaves no watcher behind"


class FlakyDevice(Mount):
    """A device whose position read fails while ``failing`` is set (a broken cable, say)."""

    def __init__(self) -> None:
        super().__init__(site=SITE)
        self.failing = False
        self.reads = 0

    poll_retry_s = 0.05

    @property
    def capabilities(self) -> Capabilities:
        return Capabilities(alignment_mode=AlignmentMode.GERMAN_POLAR)

    @property
    def identity(self) -> Identity:
        return Identity(protocol="test", model="flaky")

    async def connect(self) -> None:
        self._publish(MountState(read_at=self.now(), connected=True))

    async def disconnect(self) -> None:
        self._publish(MountState(read_at=self.now()))

    async def refresh(self) -> MountState:
        await asyncio.sleep(0.01)
        if self.failing:
            raise OSError("the serial adapter went away")
        self.reads += 1
        state = MountState(
            read_at=self.now(), connected=True, ra_j2000_hours=1.0 + self.reads * 1e-3
        )
        self._publish(state)
        return state


async def test_a_failing_poll_keeps_the_last_good_reading_and_names_the_cause() -> None:
    device = FlakyDevice()
    await device.connect()
    async with device.watching():
        good = await device.wait_for(lambda s: s.ra_j2000_hours is not None, timeout_s=2)
        device.failing = True
        broken = await device.wait_for(lambda s: bool(s.problems), timeout_s=2)
        assert "the serial adapter went away" in broken.problems[0]
        assert broken.ra_j2000_hours is not None
        assert broken.ra_j2000_hours >= good.ra_j2000_hours  # type: ignore[operator]
        reads_while_broken = device.reads
        await asyncio.sleep(0.2)
        assert device.reads == reads_while_broken
        assert device.poller.running, "the poller survives device errors"
        device.failing = False
        healed = await device.wait_for(lambda s: not s.problems, timeout_s=2)
        assert healed.ra_j2000_hours is not None
        assert healed.ra_j2000_hours > broken.ra_j2000_hours


# --- goto by name, progress, targets, park position ---------------------------------------------


async def test_goto_object_reports_progress_and_lands_on_the_object() -> None:
    mount = fast_mount()
    await mount.connect()
    found = await mount.goto_object("  capella ")
    assert found.name == "Capella"
    assert mount.target is not None
    assert mount.target.name == "Capella"
    progress: list[SlewProgress] = []
    final = await mount.wait_for_slew(timeout_s=10, progress=progress.append)
    assert not final.slewing
    distances = [p.distance_deg for p in progress if p.distance_deg is not None]
    assert len(distances) >= 3
    assert distances[0] > 10.0
    assert distances[-1] < 1.0 / 3600.0
    assert any(p.eta_s is not None and p.eta_s > 0 for p in progress[:-1])
    assert progress[-1].eta_s == 0.0
    star = lookup("Capella", mount.now(), SITE)
    assert final.ra_j2000_hours is not None
    assert final.dec_j2000_deg is not None
    miss = angular_separation_deg(
        final.ra_j2000_hours * 15, final.dec_j2000_deg, star.ra_hours * 15, star.dec_deg
    )
    assert miss < 1.0 / 3600.0


async def test_unknown_names_and_objects_below_the_horizon_move_nothing() -> None:
    mount = fast_mount()
    await mount.connect()
    before = mount.snapshot()
    with pytest.raises(UnknownObjectError, match="did you mean 'M 31'"):
        await mount.goto_object("M 311")
    with pytest.raises(LimitError):
        await mount.goto_object("Acrux")  # never rises at +45°
    assert mount.target is None
    after = mount.snapshot()
    assert not after.slewing
    assert mount.counters_at(mount.elapsed()) == pytest.approx(mount.counters_at(0.0), abs=1.0), (
        "nothing moved (tracking only)"
    )
    assert before.ra_j2000_hours is not None


def test_the_default_park_position_is_the_pole_of_the_sites_hemisphere() -> None:
    assert ParkPosition.pole(45.0) == ParkPosition(45.0, 0.0)
    assert ParkPosition.pole(-33.9) == ParkPosition(33.9, 180.0)
    assert fast_mount().park_position == ParkPosition(45.0, 0.0)


# --- the blocking facade ------------------------------------------------------------------------


def test_the_blocking_facade_drives_a_mount_from_plain_code() -> None:
    mount = fast_mount()
    with BlockingMount(mount) as blocking:
        assert blocking.state.connected
        assert blocking.identity.protocol == "simulator"
        found = blocking.goto_object("M31")
        assert found.name == "M 31"
        assert blocking.state.slewing
        final = blocking.wait_for_slew(timeout_s=10)
        assert not final.slewing
        with blocking.watching():
            fresh = blocking.wait_for(lambda s: s.read_at > final.read_at, timeout_s=2)
        assert fresh.ra_j2000_hours == pytest.approx(found.ra_hours, abs=1e-5)
        with pytest.raises(LimitError):
            blocking.goto_horizontal(-5.0, 10.0)
        with pytest.raises(TimeoutError):
            blocking.wait_for(lambda s: s.parked, timeout_s=0.1)
        assert threading.current_thread() is threading.main_thread()
    assert not mount.state.connected
    with pytest.raises(RuntimeError, match="closed"):
        blocking.refresh()


async def test_leaving_watching_mid_poll_lets_the_exchange_finish() -> None:
    # Cancelling a poll mid-exchange would make the driver resynchronise before its next command
    # (a guard watching only while a motion runs enters and leaves all the time).
    from tests.support.synscan_driver import rig

    async with rig("tcp") as bench:
        mount = bench.mount
        resyncs = mount.wire.statistics.resyncs  # connecting starts with one
        failures = mount.wire.statistics.failures
        for _ in range(10):
            async with mount.watching():
                await mount.wait_for(lambda state: True, timeout_s=5.0)
                await asyncio.sleep(0.01)  # leave with the next poll in flight
        await mount.refresh()
        assert mount.wire.statistics.resyncs == resyncs
        assert mount.wire.statistics.failures == failures
        assert not is_polling(mount)
